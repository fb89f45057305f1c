#include <tessera/graph/input_frame.hpp>

namespace tessera {

std::size_t anchor_pose(const PoseKeys& keys) {
  return keys.fixed.value_or(0);
}

void move_to_input_frame(const PoseGraph& graph, const PoseKeys& keys, std::vector<Pose>& poses) {
  if (!graph.has_initial() || poses.size() != graph.num_poses || poses.empty()) return;
  const std::size_t a = anchor_pose(keys);
  const Pose& want = graph.initial[a];
  const Pose& have = poses[a];
  const Eigen::MatrixXd R = want.R * have.R.transpose();
  const Eigen::VectorXd t = want.t - R * have.t;
  for (Pose& p : poses) {
    p.R = R * p.R;
    p.t = R * p.t + t;
  }
  poses[a] = want;  // exactly, not to the last rounding error
}

}  // namespace tessera
