#pragma once
// Step 2 of a fresh agent: what it announces to the coordinator about its robot's share —
// the structure only (pose range and measurement endpoints, never the measured values).

#include <cstdint>
#include <string>

#include "runtime/local_share.hpp"
#include "tessera.h"

namespace tessera::agent {

/// The announcement of agent `agent_id` of `num_agents` in run `run_id` for `share`, naming
/// this host and process.
wire::AgentAnnouncement announcement_of(const RobotShare& share, const std::string& run_id,
                                        std::uint32_t agent_id, std::uint32_t num_agents);

}  // namespace tessera::agent
