#pragma once
// Proj_M for several 3D poses at once, one pose a vector lane (four with AVX, two with SSE2).
// Proj_M runs on every pose of every agent several times a round (momentum's P and V, the
// update's retraction); pose by pose its 3 x 3 arithmetic is short chains that leave most of
// the vector unit idle. Each lane does the per-pose code's operations in its order
// (momentum.cpp's project_pose: the Gram entries, the binomial series for (A^T A)^{-1/2} or
// its first term, the product), so every pose gets the same bits.

#include <Eigen/Core>

namespace tessera {

/// The most poses polar_lanes_3d takes at once.
constexpr int kMaxPolarLanes = 4;

/// How many poses polar_lanes_3d takes at once here: 4 with the AVX kernels
/// (util/avx_kernels.hpp), 2 without.
int polar_lanes();

/// Replaces the 3 x 3 rotation block of each of the `lanes` (= polar_lanes()) poses at A[0..]
/// (column-major, leading dimension r: the first 3 rows of the pose's first 3 columns) by its polar
/// factor, when every one of them is within the binomial series' reach (||A^T A - I||_F < 1e-4).
/// Returns false and writes nothing otherwise: the caller then projects each pose on its own.
/// `zero_tail`: the blocks have r = 5 rows of which rows 3 and 4 are zero (a lifted start's P and
/// V), and the Gram entries are summed as the per-pose code sums them then; otherwise r = 3.
bool polar_lanes_3d(double* const* A, int lanes, Eigen::Index r, bool zero_tail);

}  // namespace tessera
