#include "certification/certificate_factor.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <stdexcept>

#include "solvers/cholmod_checked.hpp"
#include "solvers/cholmod_dense_view.hpp"
#include "solvers/pose_level_analysis.hpp"

namespace tessera {

namespace {

// S with every diagonal entry present (S + diag(D) then has the analysed pattern).
SparseMatrix with_diagonal(const SparseMatrix& S, const Eigen::VectorXd& D) {
  SparseMatrix A = S;
  for (Eigen::Index k = 0; k < A.rows(); ++k) A.coeffRef(k, k) += D(k);
  A.makeCompressed();
  return A;
}

}  // namespace

CertificateFactor::CertificateFactor(const SparseMatrix& S, int width) : n_(S.rows()) {
  cholmod_start(&c_);
  c_.print = 0;     // a matrix that is not positive definite is an expected answer
  c_.final_ll = 1;  // LL^T: LDL^T exists for indefinite matrices and would pass every test
  const SparseMatrix A = with_diagonal(S, Eigen::VectorXd::Ones(n_));
  L_ = analyse_pose_ordered(A, width, c_);
  if (!L_) {
    const int status = c_.status;
    cholmod_finish(&c_);
    throw_cholmod_failure("certificate", "analysis", status, static_cast<long>(n_),
                          static_cast<long>(n_));
  }
}

CertificateFactor::~CertificateFactor() {
  for (cholmod_dense** x : {&x_, &y_, &e_})
    if (*x) cholmod_free_dense(x, &c_);
  if (L_) cholmod_free_factor(&L_, &c_);
  cholmod_finish(&c_);
}

bool CertificateFactor::factor(const SparseMatrix& S, const Eigen::VectorXd& D) {
  const SparseMatrix A = with_diagonal(S, D);
  cholmod_sparse view = Eigen::viewAsCholmod(A.selfadjointView<Eigen::Lower>());
  cholmod_factorize(&view, L_, &c_);
  if (c_.status < CHOLMOD_OK)
    throw_cholmod_failure("certificate", "factorization", c_.status, static_cast<long>(n_),
                          static_cast<long>(n_));
  return L_->minor == L_->n;  // else not positive definite (CHOLMOD's warning, not an error)
}

void CertificateFactor::solve(const double* x, double* y) const {
  cholmod_dense b = cholmod_dense_view(x, n_);
  if (!cholmod_solve2(CHOLMOD_A, L_, &b, nullptr, &x_, nullptr, &y_, &e_, &c_))
    throw std::runtime_error("certificate: CHOLMOD's solve failed");
  std::copy_n(static_cast<const double*>(x_->x), n_, y);
}

}  // namespace tessera
