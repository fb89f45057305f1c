#pragma once
// Optimal translations for fixed rotations: a weighted graph-Laplacian least-squares
// problem, solved with a sparse Cholesky factorization (CHOLMOD). Pose `anchor` is fixed
// at the origin; the objective is invariant to a global translation, so this loses nothing.

#include <Eigen/Core>
#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// Returns t (d x n) minimising sum_e tau ||t_j - t_i - R_i t_ij||^2 given R_i (d x dn).
/// Requires a connected graph.
Eigen::MatrixXd solve_translations(const PoseGraph& graph, const Eigen::MatrixXd& rotations,
                                   std::size_t anchor = 0);

}  // namespace tessera
