#pragma once
// The tangent preconditioner's coordinate maps for 3D poses (tangent_coordinates.hpp's
// tangent_coordinates<3> and tangent_vector<3>) several poses at once, one a vector lane (four
// with AVX, two with SSE2; manifold/pose_lanes.hpp's pose_lanes()). Each lane does the per-pose
// code's operations in its order, so the same bits. Each call takes the whole groups among the
// m poses and returns how many poses it did; the caller does the rest pose by pose.

#include <Eigen/Core>

namespace tessera {

/// b = J^T V for the first poses of X (3 x 4 each, rank 3) and V; 6 coordinates a pose.
Eigen::Index tangent_coordinates_in_lanes(const double* X, const double* V, Eigen::Index m,
                                          double* b);

/// Z = J c for the first poses of X and c (6 coordinates a pose); Z 3 x 4 a pose.
Eigen::Index tangent_vector_in_lanes(const double* X, const double* c, Eigen::Index m, double* Z);

}  // namespace tessera
