#include "solvers/block_preconditioner.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/CholmodSupport>

namespace tessera {

struct BlockPreconditioner::Factors {
  Eigen::CholmodSupernodalLLT<SparseMatrix> base;      // Q + lambda I, always valid
  Eigen::CholmodSupernodalLLT<SparseMatrix> adaptive;  // S(X) + mu I, when PD
  bool adaptive_valid = false;
  bool adaptive_analyzed = false;
};

BlockPreconditioner::BlockPreconditioner(const BlockProblem& problem, double relative_shift)
    : problem_(problem), factors_(std::make_unique<Factors>()) {
  const SparseMatrix& Q = problem.data_matrix();
  shift_ = relative_shift * std::max(1e-12, Q.rows() ? Q.diagonal().maxCoeff() : 1.0);
  SparseMatrix A = Q;
  for (Eigen::Index k = 0; k < A.rows(); ++k) A.coeffRef(k, k) += shift_;
  factors_->base.compute(A);
  if (factors_->base.info() != Eigen::Success)
    throw std::runtime_error("BlockPreconditioner: Cholesky factorization failed");
}

BlockPreconditioner::~BlockPreconditioner() = default;

bool BlockPreconditioner::update(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad) {
  const int d = problem_.dim();
  SparseMatrix A = problem_.data_matrix();
  // Lambda_i = sym(Y_i^T G_i) with G = egrad / 2, on the rotation blocks (same pattern as Q).
  const Eigen::Index n = static_cast<Eigen::Index>(problem_.num_owned());
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index c = (d + 1) * i;
    Eigen::MatrixXd L = 0.5 * (X.middleCols(c, d).transpose() * egrad.middleCols(c, d));
    L = 0.5 * (L + L.transpose());
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) A.coeffRef(c + a, c + b) -= L(a, b);
  }
  for (Eigen::Index k = 0; k < A.rows(); ++k) A.coeffRef(k, k) += shift_;
  if (!factors_->adaptive_analyzed) {
    factors_->adaptive.analyzePattern(A);
    factors_->adaptive_analyzed = true;
  }
  factors_->adaptive.factorize(A);
  factors_->adaptive_valid = factors_->adaptive.info() == Eigen::Success;
  return factors_->adaptive_valid;
}

Eigen::MatrixXd BlockPreconditioner::apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                                           const Eigen::MatrixXd& V) const {
  Eigen::MatrixXd Vt = V.transpose();
  Eigen::MatrixXd Z = factors_->adaptive_valid ? Eigen::MatrixXd(factors_->adaptive.solve(Vt))
                                               : Eigen::MatrixXd(factors_->base.solve(Vt));
  return manifold.tangent_project(X, 0.5 * Z.transpose());
}

}  // namespace tessera
