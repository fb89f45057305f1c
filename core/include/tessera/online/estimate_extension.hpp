#pragma once
// Initial values of poses that joined a running optimisation: composed from the current
// estimate through the measurements that link them to it, so a new pose starts where its
// odometry (or a loop closure) puts it relative to the already optimised trajectory, not in
// its front end's drifting frame. In the lifted problem this is exact composition:
// measurement i -> j gives Y_j = Y_i R_ij and p_j = p_i + Y_i t_ij (and the inverse when j is
// known), which keeps Y_j in St(d, r), so the warm start stays a valid point of the manifold.

#include <Eigen/Core>
#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct EstimateExtension {
  /// r x (d+1)n: the old iterate followed by the new poses' lifted values.
  Eigen::MatrixXd X;
  std::size_t composed = 0;  ///< New poses reached through a measurement.
  /// New poses with no measurement path to an estimated pose (a robot's first poses before
  /// its first closure): the first of each such piece is lifted from its front end's guess
  /// ([R; 0], [t; 0]) and the rest of the piece is composed from it.
  std::size_t from_guess = 0;
};

/// Extends `X` (r x (d+1)m, poses 0..m-1 of `graph`) to all graph.num_poses poses. Poses are
/// visited breadth first from the estimated ones over the measurements in graph order, so a
/// chain of new poses is composed pose after pose along its odometry. `guesses` (graph.d,
/// one per pose of the graph) seed the unreachable pieces. `first_new_measurement`: the
/// measurements before it touch none of the new poses (they were there before the new poses
/// arrived), so only the rest is read and the cost follows the new data, not the graph; the
/// result is the same as with 0. Throws std::invalid_argument when sizes do not fit.
EstimateExtension extend_estimate(const PoseGraph& graph, const Eigen::MatrixXd& X,
                                  const std::vector<Pose>& guesses,
                                  std::size_t first_new_measurement = 0);

}  // namespace tessera
