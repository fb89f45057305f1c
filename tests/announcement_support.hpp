#pragma once
// What the agents of a run on a pose graph announce to the coordinator (agent k announces
// robot k's share, agent/share_announcement.hpp), built without a participant, for tests of
// the coordinator's structure and partition.

#include <cstdint>
#include <vector>

#include "agent/share_announcement.hpp"
#include "runtime/local_share.hpp"

namespace tessera::test {

/// The N announcements of a run on `g` (run id "r"), in agent order.
inline std::vector<wire::AgentAnnouncement> announcements_of(const PoseGraph& g, std::uint32_t N) {
  std::vector<wire::AgentAnnouncement> out;
  for (std::uint32_t k = 0; k < N; ++k)
    out.push_back(agent::announcement_of(agent::robot_share(g, k, N), "r", k, N));
  return out;
}

}  // namespace tessera::test
