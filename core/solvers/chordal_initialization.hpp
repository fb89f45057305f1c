#pragma once
// Chordal initialization: relax the rotations to unconstrained d x d matrices, solve the
// resulting sparse linear least-squares problem (CHOLMOD; pose 0 anchored at identity),
// project each block onto SO(d), then solve the translations optimally for those rotations.

#include <vector>

#include "graph/pose.hpp"
#include "graph/pose_graph.hpp"

namespace tessera {

std::vector<Pose> chordal_initialization(const PoseGraph& graph);

/// Only the rotations, d x dn.
Eigen::MatrixXd chordal_rotations(const PoseGraph& graph);

}  // namespace tessera
