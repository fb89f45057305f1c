#pragma once
// Global-optimality certificate for a first-order critical point X of the lifted problem
// (SE-Sync's verification): with the Lagrange multipliers Lambda = BlockDiag(sym(Y_i^T (XQ)_i))
// (zero on translations), X is globally optimal for the SDP relaxation iff
// S = Q - Lambda is positive semidefinite. Numerically: certified when lambda_min(S) >= -eta.
//
// The test is a sparse Cholesky factorization of S + eta I (it exists iff lambda_min > -eta);
// the minimum eigenvalue itself is then found by Lanczos (Spectra) on a shift-invert operator,
// so it converges in a few steps even on large graphs. When the test fails, the shift is
// pushed down until the factorization exists and the same operator yields the most negative
// eigenvalue and its eigenvector (the saddle-escape direction).

#include <Eigen/Core>
#include <string>
#include <tessera/problem/block_problem.hpp>

namespace tessera {

struct CertificateOptions {
  /// eta = relative_tolerance * max(1, max diagonal entry of Q). >= 0.
  double relative_tolerance = 1e-6;
  int lanczos_max_iterations = 1000;  ///< > 0
  double lanczos_tolerance = 1e-8;    ///< Relative accuracy of the eigenvalue, > 0.
  void validate() const;
};

struct CertificateResult {
  bool certified = false;
  /// lambda_min(S) (estimate); NaN if Lanczos did not converge (the factorization test still
  /// decides `certified`).
  double min_eigenvalue = 0.0;
  double tolerance = 0.0;  ///< The absolute eta used.
  /// Unit eigenvector of lambda_min, length (d+1)n, set when not certified.
  Eigen::VectorXd min_eigenvector;
  int factorizations = 0;
  int lanczos_iterations = 0;
  double elapsed_s = 0.0;
};

/// `problem` must own every pose (no neighbours): the centralized problem.
CertificateResult verify_certificate(const BlockProblem& problem, const Eigen::MatrixXd& X,
                                     const CertificateOptions& options = {});

/// S = Q - Lambda(X), exposed for tests and for distributed certification.
SparseMatrix certificate_matrix(const BlockProblem& problem, const Eigen::MatrixXd& X);

}  // namespace tessera
