#include <tessera/graph/robot_summary.hpp>

namespace tessera {

RobotSummary summarize_robots(const PoseGraph& graph, const PoseKeys& keys) {
  RobotSummary s;
  s.robots.resize(keys.num_robots());
  for (std::size_t r = 0; r < s.robots.size(); ++r) s.robots[r].name = keys.robot_name(r);
  for (std::size_t k = 0; k < graph.num_poses; ++k) ++s.robots[keys.robot_of(k)].poses;
  for (const Measurement& m : graph.measurements) {
    const std::uint32_t a = keys.robot_of(m.i), b = keys.robot_of(m.j);
    if (a != b) {
      ++s.robots[a].inter_closures;
      ++s.robots[b].inter_closures;
      ++s.inter_closures;
      continue;
    }
    const std::uint64_t u = keys.index_in_robot(m.i), v = keys.index_in_robot(m.j);
    if (u + 1 == v || v + 1 == u) {
      ++s.robots[a].odometry;
      ++s.odometry;
    } else {
      ++s.robots[a].intra_closures;
      ++s.intra_closures;
    }
  }
  return s;
}

}  // namespace tessera
