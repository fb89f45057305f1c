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
  /// Krylov dimension of the Lanczos run from a random start (the saddle's eigenpair), in
  /// [3, 1000]. Wide: near a certified optimum the top of the shift-inverted spectrum is a
  /// cluster (S's null space), which a narrow space resolves slowly.
  int lanczos_subspace = 40;
  /// Krylov dimension, in [3, 1000], of the run that only reports lambda_min once the
  /// factorization has certified X. That run starts from the sum of X's rows, which S maps to
  /// (about) zero at a critical point (S X^T = 0 is the first-order condition), so the top of
  /// the inverted spectrum is found at once: 7 solves instead of 41 on city10000 and cubicle,
  /// the same lambda_min to 1e-3 eta.
  int certified_lanczos_subspace = 6;
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
  int lanczos_iterations = 0;  ///< Lanczos restarts over every run.
  int lanczos_solves = 0;      ///< Solves with a factor (shift-inverted operator applications).
  double elapsed_s = 0.0;
};

/// `problem` must own every pose (no neighbours): the centralized problem. X is a first-order
/// critical point when the certificate is to mean anything (the warm start assumes it too).
CertificateResult verify_certificate(const BlockProblem& problem, const Eigen::MatrixXd& X,
                                     const CertificateOptions& options = {});

/// S = Q - Lambda(X), exposed for tests and for distributed certification.
SparseMatrix certificate_matrix(const BlockProblem& problem, const Eigen::MatrixXd& X);

}  // namespace tessera
