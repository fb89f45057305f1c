#pragma once
// Preconditioner for trust-region steps on a BlockProblem.
//
// Near a critical point the Riemannian Hessian is Hess f(X)[V] = 2 P_X(V S) with
// S = Q - Lambda(X) the certificate matrix, so the natural preconditioner is
// (2 (S + mu I))^{-1} followed by the tangent projection. Far from a critical point S + mu I
// may be indefinite; then the always-valid 2 (Q + lambda I) is used. Both are sparse
// Cholesky factorizations (CHOLMOD) sharing one symbolic analysis; refreshing the S-based one
// costs a numeric factorization, done at most once per accepted trust-region step.

#include <memory>

#include <Eigen/Core>

#include "problem/block_problem.hpp"

namespace tessera {

class BlockPreconditioner {
 public:
  /// `relative_shift`: lambda = mu = relative_shift * max diagonal entry of Q_BB.
  explicit BlockPreconditioner(const BlockProblem& problem, double relative_shift = 1e-6);
  ~BlockPreconditioner();
  BlockPreconditioner(const BlockPreconditioner&) = delete;
  BlockPreconditioner& operator=(const BlockPreconditioner&) = delete;

  /// Re-bases the preconditioner on S(X) = Q_BB - Lambda(X); falls back to Q_BB when S + mu I
  /// is not positive definite. Returns true when the S-based factor is in use.
  bool update(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad);

  /// Tangent projection at X of (2 (A + shift I))^{-1} applied to the rows of V.
  Eigen::MatrixXd apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                        const Eigen::MatrixXd& V) const;

 private:
  struct Factors;
  const BlockProblem& problem_;
  double shift_;
  std::unique_ptr<Factors> factors_;
};

}  // namespace tessera
