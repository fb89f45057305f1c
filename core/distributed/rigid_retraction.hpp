#pragma once
// Internal: the retraction the Newton refinement moves its trial points with.

#include <Eigen/Core>
#include <tessera/manifold/lifted_manifold.hpp>

namespace tessera {

/// X moved along the tangent vector s, pose by pose, by the exponential of the pose's own
/// world-frame twist: (R, t) -> (exp(W) R, exp(W) t + V(W) v), with W = s_R R^T (skew) and
/// v = s_t - W t, V the left Jacobian of SE(d) (so this is the SE(d) exponential map).
///
/// Why not the polar retraction with additive translations: a Newton step on a long chain
/// turns whole parts of the map by tenths of a radian about points hundreds of metres away
/// (ais2klinik: -0.19 and +0.14 rad, translations moved by up to 74 m). Adding the first-order
/// translation step to a finitely turned rotation stretches every edge by sqrt(1 + theta^2)
/// and shifts each part by ~theta^2/2 times its distance to the origin: f rose by 178 where the
/// quadratic model predicted a decrease of 0.047. Poses that share a twist (a part turning as
/// one piece) move rigidly here, exactly, whatever the angle.
///
/// Needs R square (X.rows() == d, the usual case: an iterate lifted from dimension d keeps its
/// other rows zero and the refinement works on the rows in use); for a rank-lifted X
/// (rows > d) it is the manifold's polar retraction.
Eigen::MatrixXd retract_rigid(const LiftedManifold& manifold, int d, const Eigen::MatrixXd& X,
                              const Eigen::MatrixXd& s);

}  // namespace tessera
