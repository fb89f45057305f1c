#pragma once
// What the agents of a run on a pose graph announce to the coordinator (agent/run_setup.cpp:
// robot k's share of the measurements), built without a participant, for tests of the
// coordinator's structure and partition.

#include <cstdint>
#include <vector>

#include "agent/local_share.hpp"
#include "coordinator/run_structure.hpp"

namespace tessera::test {

/// The N announcements of a run on `g` (run id "r", host "h"), in agent order.
inline std::vector<wire::AgentAnnouncement> announcements_of(const PoseGraph& g, std::uint32_t N) {
  std::vector<wire::AgentAnnouncement> out;
  for (std::uint32_t k = 0; k < N; ++k) {
    const agent::RobotShare s = agent::robot_share(g, k, N);
    wire::AgentAnnouncement a;
    a.run_id("r");
    a.agent_id(k);
    a.num_agents(N);
    a.host("h");
    a.dim(static_cast<std::uint32_t>(g.d));
    a.num_poses(static_cast<std::uint32_t>(g.num_poses));
    a.pose_begin(s.begin);
    a.pose_end(s.end);
    for (const auto& m : s.measurements) {
      a.edge_i().push_back(static_cast<std::uint32_t>(m.i));
      a.edge_j().push_back(static_cast<std::uint32_t>(m.j));
    }
    a.edge_index(s.measurement_index);
    out.push_back(a);
  }
  return out;
}

}  // namespace tessera::test
