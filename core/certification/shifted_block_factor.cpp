#include "certification/shifted_block_factor.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <stdexcept>

#include "solvers/cholmod_checked.hpp"
#include "solvers/cholmod_dense_view.hpp"
#include "solvers/pose_level_analysis.hpp"
#include "util/serial_blas.hpp"

namespace tessera {

ShiftedBlockFactor::ShiftedBlockFactor(const SparseMatrix& S, int width) {
  cholmod_start(&c_);
  c_.print = 0;  // a matrix that is not positive definite is an expected answer (a larger shift)
  c_.supernodal = CHOLMOD_SUPERNODAL;
  c_.final_ll = 1;
  const Eigen::Index n = S.rows();
  L_ = analyse_pose_ordered(S, width, c_);
  if (!L_) {
    const int status = c_.status;
    cholmod_finish(&c_);
    throw_cholmod_failure("certificate (block preconditioner)", "analysis", status,
                          static_cast<long>(n), static_cast<long>(n));
  }
}

ShiftedBlockFactor::~ShiftedBlockFactor() {
  for (cholmod_dense** x : {&x_, &y_, &e_})
    if (*x) cholmod_free_dense(x, &c_);
  if (L_) cholmod_free_factor(&L_, &c_);
  cholmod_finish(&c_);
}

bool ShiftedBlockFactor::factor(const SparseMatrix& S, double shift) {
  if (!L_->is_super)
    throw std::logic_error("ShiftedBlockFactor::factor: the matrix was factored already");
  cholmod_sparse view = Eigen::viewAsCholmod(S.selfadjointView<Eigen::Lower>());
  double beta[2] = {shift, 0.0};  // factors S + beta[0] I
  {
    const SerialBlasLock lock(serial_blas_mutex());  // CHOLMOD's supernodal kernels call BLAS
    cholmod_factorize_p(&view, beta, nullptr, 0, L_, &c_);
  }
  if (c_.status < CHOLMOD_OK)
    throw_cholmod_failure("certificate (block preconditioner)", "factorization", c_.status,
                          static_cast<long>(S.rows()), static_cast<long>(S.cols()));
  if (L_->minor < L_->n) return false;  // not positive definite: the caller shifts further
  if (!cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/0, /*to_super=*/0, /*to_packed=*/1,
                             /*to_monotonic=*/1, L_, &c_))
    throw_cholmod_failure("certificate (block preconditioner)", "factor conversion", c_.status,
                          static_cast<long>(S.rows()), static_cast<long>(S.cols()));
  chain_.build(L_);
  return true;
}

Eigen::MatrixXd ShiftedBlockFactor::solve(const Eigen::MatrixXd& r) {
  Eigen::MatrixXd out(r.rows(), r.cols());
  if (chain_.ready() && r.rows() == 1) {
    chain_.solve(L_, r.data(), out.data());
    return out;
  }
  // One row: its entries are contiguous.
  cholmod_dense b = cholmod_dense_view(r.data(), r.cols());
  if (r.rows() != 1 || !cholmod_solve2(CHOLMOD_A, L_, &b, nullptr, &x_, nullptr, &y_, &e_, &c_))
    throw std::runtime_error("certificate (block preconditioner): solve failed");
  std::copy_n(static_cast<const double*>(x_->x), r.cols(), out.data());
  return out;
}

}  // namespace tessera
