#pragma once
// Per-pose kernels of the 3D agents for several poses at once, one pose a vector lane (four
// with AVX, two with SSE2): Proj_M, the tangent projection and the Riemannian Hessian's
// projection. They run on every pose of every agent several times a round; pose by pose their
// 3 x 3 arithmetic is short chains that leave most of the vector unit idle. Each lane does the
// per-pose code's operations in its order, so every pose gets the same bits as pose by pose.
//
// The poses of a group are consecutive: pose l's r x 4 block (column-major, leading dimension
// r; its first 3 columns the rotation, the 4th the translation) starts at 4 r l.

#include <Eigen/Core>

namespace tessera {

/// The most poses a group holds.
constexpr int kMaxPoseLanes = 4;

/// How many poses a group holds here: 4 with the AVX kernels (util/avx_kernels.hpp), 2 without.
int pose_lanes();

/// Proj_M (momentum.cpp's project_pose) on the rotation blocks of a group of `lanes` poses at A,
/// when every one of them is within the binomial series' reach (||A^T A - I||_F < 1e-4).
/// Returns false and writes nothing otherwise: the caller then projects each pose on its own.
/// r = 3, or r = 5 with rows 3 and 4 zero (a lifted start's P and V; the Gram entries are then
/// summed as the per-pose code sums them).
bool polar_in_lanes(double* A, int lanes, Eigen::Index r);

/// The tangent projection at X (lifted_manifold.cpp's tangent_project_poses<3, 3>) of V's
/// rotation columns into out's, for a group at r = 3. out may be V; translations untouched.
void tangent_project_in_lanes(const double* X, const double* V, int lanes, double* out);

/// The Hessian's projection (pose_kernels.cpp's hessian_projection<3, 3>) for a group at r = 3:
/// H's rotation columns -= X sym(X^T H) + V sym(X^T G), translations untouched.
void hessian_projection_in_lanes(const double* X, const double* G, const double* V, int lanes,
                                 double* H);

}  // namespace tessera
