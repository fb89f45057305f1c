#pragma once
// Global-optimality certificate of the lifted problem (SE-Sync's verification, made to hold at
// any point): with the Lagrange multipliers Lambda = BlockDiag(sym(Y_i^T (XQ)_i)) (zero on
// translations) and S = Q - Lambda, X is globally optimal for the SDP relaxation iff S is
// positive semidefinite AND X is first-order critical. No solver reaches an exact critical
// point, so lambda_min(S) >= -eta alone is no certificate: parking-garage's RBCD iterate at
// |grad f| = 0.0097 passed it 7e-4 relative above f*. What is certified is the weak-duality
// bound of dual_bound.hpp, proved by factorizations of S + D: certified when f(X) - f_lb is
// within suboptimality_tolerance.
//
// The saddle test is a sparse Cholesky factorization of S + eta I (it exists iff
// lambda_min > -eta); the minimum eigenvalue itself is then found by Lanczos (Spectra) on a
// shift-invert operator, so it converges in a few steps even on large graphs. When the test
// fails, the shift is pushed down until the factorization exists and the same operator yields
// the most negative eigenvalue and its eigenvector (the saddle-escape direction).

#include <Eigen/Core>
#include <string>
#include <tessera/certification/dual_bound.hpp>
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
  /// `certified` also needs the weak-duality bound (dual_bound.hpp) proved and within this
  /// relative tolerance: (f(X) - f_lb) <= suboptimality_tolerance * max(1, |f(X)|). >= 0.
  double suboptimality_tolerance = kDefaultSuboptimalityTolerance;
  void validate() const;
};

struct CertificateResult {
  /// The bound (below) proved and within suboptimality_tolerance: X is then within that
  /// relative distance of the optimum (dual_bound.hpp).
  bool certified = false;
  /// S + eta I factored: lambda_min(S) > -eta. At a point that is not first-order critical
  /// this alone proves nothing about optimality (the bound says how far from it X is).
  bool psd_within_tolerance = false;
  /// The weak-duality lower bound at X and its proof (always computed).
  DualBound bound;
  /// lambda_min(S) (estimate); NaN if Lanczos did not converge (the factorization test still
  /// decides `certified`).
  double min_eigenvalue = 0.0;
  double tolerance = 0.0;  ///< The absolute eta used.
  /// Unit eigenvector of lambda_min, length (d+1)n, set when not certified.
  Eigen::VectorXd min_eigenvector;
  int factorizations = 0;        ///< Every one, proof_factorizations included.
  int proof_factorizations = 0;  ///< Of S + D for the bound.
  int lanczos_iterations = 0;    ///< Lanczos restarts over every run.
  int lanczos_solves = 0;        ///< Solves with a factor (shift-inverted operator applications).
  double elapsed_s = 0.0;
};

/// `problem` must own every pose (no neighbours): the centralized problem. At any X, critical or
/// not, `bound` is proved by factorizations of S + D (dual_bound.hpp), its floor from
/// first_proof_shift up by factors of kProofShiftGrowth; `certified` needs it within
/// suboptimality_tolerance.
CertificateResult verify_certificate(const BlockProblem& problem, const Eigen::MatrixXd& X,
                                     const CertificateOptions& options = {});

/// S = Q - Lambda(X), exposed for tests and for distributed certification.
SparseMatrix certificate_matrix(const BlockProblem& problem, const Eigen::MatrixXd& X);

}  // namespace tessera
