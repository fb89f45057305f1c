#include "solvers/block_preconditioner.hpp"

#include <Eigen/CholmodSupport>
#include <stdexcept>

namespace tessera {

struct BlockPreconditioner::Factor {
  // Simplicial LDL^T. The factor is computed once and solved against thousands of times with
  // only r (= d, mostly) right-hand sides, where the supernodal solve's BLAS calls on small
  // supernodes cost more than they save: measured CPU per solve, simplicial LDL^T vs CHOLMOD's
  // automatic choice (supernodal on these graphs): city10000 2.6 vs 4.8 ms, sphere2500 1.2 vs
  // 2.0 ms, cubicle 5.0 vs 5.9 ms, ais2klinik 0.78 vs 0.72 ms (docs/centralized-solver.md).
  Eigen::CholmodDecomposition<SparseMatrix> llt;
};

BlockPreconditioner::BlockPreconditioner(const BlockProblem& problem, double relative_shift)
    : factor_(std::make_unique<Factor>()) {
  const SparseMatrix& Q = problem.data_matrix();
  const double lambda = relative_shift * std::max(1e-12, Q.diagonal().maxCoeff());
  SparseMatrix A = Q;
  for (Eigen::Index k = 0; k < A.rows(); ++k) A.coeffRef(k, k) += lambda;
  factor_->llt.setMode(Eigen::CholmodLDLt);
  factor_->llt.compute(A);
  if (factor_->llt.info() != Eigen::Success)
    throw std::runtime_error("BlockPreconditioner: Cholesky factorization failed");
}

BlockPreconditioner::~BlockPreconditioner() = default;

Eigen::MatrixXd BlockPreconditioner::apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                                           const Eigen::MatrixXd& V) const {
  Eigen::MatrixXd Vt = V.transpose();
  Eigen::MatrixXd Z = factor_->llt.solve(Vt).transpose();
  return manifold.tangent_project(X, 0.5 * Z);
}

}  // namespace tessera
