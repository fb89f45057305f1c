#pragma once
// The PGO objective on SE(d) in the reference convention (../shared/reference/README.md):
//   f = sum_e kappa ||R_j - R_i R_ij||_F^2 + tau ||t_j - t_i - R_i t_ij||^2   (the full sum).

#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// f of `poses` (one per graph pose, in id order) summed over every measurement of the graph,
/// in measurement order. Throws std::invalid_argument when poses.size() != graph.num_poses.
double evaluate_objective(const PoseGraph& graph, const std::vector<Pose>& poses);

}  // namespace tessera
