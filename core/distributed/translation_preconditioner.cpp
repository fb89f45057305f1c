#include "distributed/translation_preconditioner.hpp"

#include <algorithm>
#include <vector>

namespace tessera {

TranslationPreconditioner::TranslationPreconditioner(const BlockProblem& problem)
    : dim_(problem.dim()), poses_(static_cast<Eigen::Index>(problem.num_owned())) {
  // L_BB is Q_BB's translation-translation part (each pose's last column).
  const SparseMatrix& Q = problem.data_matrix();
  const int w = dim_ + 1;
  const Eigen::Index m = poses_;
  std::vector<Eigen::Triplet<double>> trip;
  for (int k = 0; k < Q.outerSize(); ++k) {
    if (k % w != w - 1) continue;
    for (SparseMatrix::InnerIterator it(Q, k); it; ++it)
      if (it.row() % w == w - 1) trip.emplace_back(it.row() / w, k / w, it.value());
  }
  SparseMatrix L(m, m);
  L.setFromTriplets(trip.begin(), trip.end());
  ldlt_.compute(L);
  if (ldlt_.info() != Eigen::Success) {
    // A block with no cut measurement (one agent): L_BB is singular on the constants. Any
    // positive definite preconditioner serves CG; a shift of 1e-9 of the largest weight does.
    double top = 0.0;
    for (Eigen::Index i = 0; i < m; ++i) top = std::max(top, L.coeff(i, i));
    SparseMatrix I(m, m);
    I.setIdentity();
    ldlt_.compute(L + 1e-9 * std::max(top, 1.0) * I);
  }
}

void TranslationPreconditioner::apply(const Eigen::MatrixXd& r, Eigen::MatrixXd& z) {
  const int w = dim_ + 1;
  const Eigen::Index m = poses_;
  // resize and the solve's assignment keep the storage of a buffer that has the size already
  // (every iteration of a trial's solve).
  rt_.resize(m, r.rows());
  for (Eigen::Index i = 0; i < m; ++i) rt_.row(i) = r.col(i * w + w - 1).transpose();
  zt_ = ldlt_.solve(rt_);
  z.setZero(r.rows(), r.cols());
  for (Eigen::Index i = 0; i < m; ++i) z.col(i * w + w - 1) = 0.5 * zt_.row(i).transpose();
}

void TranslationPreconditioner::keep_translations(int dim, Eigen::MatrixXd& v) {
  const Eigen::Index w = dim + 1;
  for (Eigen::Index c = 0; c < v.cols(); ++c)
    if (c % w != w - 1) v.col(c).setZero();
}

}  // namespace tessera
