#pragma once
// What the truncated-CG trust region needs from a preconditioner: a symmetric positive definite
// map of the tangent space at X to itself, approximating the inverse Riemannian Hessian there.

#include <Eigen/Core>
#include <tessera/manifold/lifted_manifold.hpp>

namespace tessera {

class RiemannianPreconditioner {
 public:
  virtual ~RiemannianPreconditioner() = default;
  /// The preconditioned tangent vector at X of the tangent vector V (both r x (d+1)m).
  virtual Eigen::MatrixXd apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                                const Eigen::MatrixXd& V) const = 0;
  /// True when the next apply() will use a different operator (a preconditioner that decided
  /// to build a better factor). CG needs one fixed preconditioner, so the caller ends its inner
  /// solve there and does not reuse vectors preconditioned before.
  virtual bool changes_at_next_apply() const { return false; }
};

}  // namespace tessera
