#pragma once
// New poses placed by least squares against every new measurement, after composition
// (estimate_extension.hpp) put them where their odometry chains lead. Why: composition follows one
// path from the estimate and ignores the new loop closures, so a chain of new poses drifts away
// from the places it closes on; on a generated 1,000-pose 3D grid (5 robots, 50 new poses a step)
// the composed start was 80 % above the step's optimum and the first Newton step of every online
// step worked in the nonlinear regime (|grad f| 1e4 -> 800). This is the chordal relaxation of the
// new poses alone, the estimated poses held fixed: rotations by linear least squares
// (sum kappa ||Y_j - Y_i R_ij||^2, a connection Laplacian over the new poses) projected onto
// St(d, r), then translations by linear least squares with those rotations (a weighted graph
// Laplacian). Where every new measurement placed a new pose (a tree: odometry only) composition is
// already exact and nothing is done. A piece of new poses with no measurement to an estimated pose
// (a robot's first poses) has no anchor and keeps its composed values.

#include <Eigen/Core>
#include <cstddef>
#include <tessera/graph/pose_graph.hpp>

namespace tessera {

/// What place_new_poses did.
struct NewPosePlacement {
  std::size_t placed = 0;        ///< New poses re-placed (0: nothing to do).
  std::size_t measurements = 0;  ///< Measurements in the least-squares problems.
};

/// `X` (r x (d+1) graph.num_poses): poses 0..first_new_pose-1 estimated, the rest composed
/// (extend_estimate). Re-places the new poses that some new measurement links to an estimated
/// pose (through other new poses or not) when the new measurements form a cycle with them.
/// `first_new_measurement`: the measurements before it touch no new pose. Deterministic (the same
/// result on every agent that holds the same graph and X). Throws std::invalid_argument when
/// sizes do not fit.
NewPosePlacement place_new_poses(const PoseGraph& graph, Eigen::MatrixXd& X,
                                 std::size_t first_new_pose, std::size_t first_new_measurement);

}  // namespace tessera
