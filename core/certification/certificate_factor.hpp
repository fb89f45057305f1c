#pragma once
// The centralized certificate's sparse LL^T of S + D (S = Q - Lambda, D diagonal): analysed
// once, factored for each diagonal D the certificate tries (the proof's S + D, the saddle
// test's S + eta I, a tighter shift for the escape direction), solved against for Lanczos.
//
// How: ordered at the pose level (CHOLMOD's AMD on the m x m pattern of S's pose blocks, each
// pose's d + 1 coordinates kept together, as ShiftedBlockFactor; the analysis costs (d+1)^2
// times less than AMD on the coordinates), one symbolic analysis for every factorization (the
// matrices differ on the diagonal only), simplicial or supernodal by CHOLMOD's flop rule (dense
// kernels on the 3D graphs, simplicial on the 2D ones). LL^T in both: it fails exactly when the
// matrix is not positive definite, which is the test.

#include <cholmod.h>

#include <Eigen/Core>
#include <tessera/problem/data_matrix.hpp>

namespace tessera {

class CertificateFactor {
 public:
  /// Analyses the pattern of `S` with its diagonal (square, `width` coordinates a pose; the
  /// lower triangle is read). Throws (throw_cholmod_failure) when CHOLMOD's analysis fails.
  CertificateFactor(const SparseMatrix& S, int width);
  ~CertificateFactor();
  CertificateFactor(const CertificateFactor&) = delete;
  CertificateFactor& operator=(const CertificateFactor&) = delete;

  /// Factors S + diag(D) (`D`: one entry a coordinate). False when it is not positive
  /// definite; a CHOLMOD error (out of memory) throws.
  bool factor(const SparseMatrix& S, const Eigen::VectorXd& D);
  /// y = (S + diag(D))^{-1} x with the last successful factorization.
  void solve(const double* x, double* y) const;
  Eigen::Index rows() const { return n_; }

 private:
  mutable cholmod_common c_;
  cholmod_factor* L_ = nullptr;
  Eigen::Index n_ = 0;
  mutable cholmod_dense *x_ = nullptr, *y_ = nullptr, *e_ = nullptr;  // solve workspace
};

}  // namespace tessera
