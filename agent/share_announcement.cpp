#include "agent/share_announcement.hpp"

#include <unistd.h>

#include "transport/run_identity.hpp"

namespace tessera::agent {

wire::AgentAnnouncement announcement_of(const RobotShare& share, const std::string& run_id,
                                        std::uint32_t agent_id, std::uint32_t num_agents) {
  wire::AgentAnnouncement ann;
  ann.run_id(run_id);
  ann.agent_id(agent_id);
  ann.num_agents(num_agents);
  ann.host(transport::host_name());
  ann.pid(static_cast<std::uint32_t>(getpid()));
  ann.dim(static_cast<std::uint32_t>(share.d));
  ann.num_poses(static_cast<std::uint32_t>(share.num_poses));
  ann.pose_begin(share.begin);
  ann.pose_end(share.end);
  for (const Measurement& m : share.measurements) {
    ann.edge_i().push_back(static_cast<std::uint32_t>(m.i));
    ann.edge_j().push_back(static_cast<std::uint32_t>(m.j));
  }
  ann.edge_index(share.measurement_index);
  ann.known_inlier_index(share.known_inlier_index);
  return ann;
}

}  // namespace tessera::agent
