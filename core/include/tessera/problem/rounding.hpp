#pragma once
// Rounding a lifted solution X (r x (d+1)n) back to poses in SE(d), as in SE-Sync:
// the rank-d truncation of the stacked Stiefel blocks, each block projected onto SO(d)
// (with the reflection chosen so most blocks have det +1), then the translations that are
// optimal for those rotations.

#include <Eigen/Core>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// Rotations only: d x dn, [R_1 ... R_n].
Eigen::MatrixXd round_rotations(const Eigen::MatrixXd& X, int d);

/// Full rounding: rotations from round_rotations, translations re-solved optimally.
std::vector<Pose> round_solution(const PoseGraph& graph, const Eigen::MatrixXd& X);

/// Assembles poses from d x dn rotations and d x n translations.
std::vector<Pose> assemble_poses(const Eigen::MatrixXd& rotations,
                                 const Eigen::MatrixXd& translations);

}  // namespace tessera
