#pragma once
// Step 1 of a run on the coordinator's side: waiting until every agent has announced its
// share of the graph structure (TRANSIENT_LOCAL, so agents may have started first).

#include <cstdint>
#include <string>
#include <vector>

#include "tessera.h"
#include "transport/coordinator_session.hpp"

namespace tessera::coordinator {

/// Waits up to `timeout_s` for the announcements of agents 0..num_agents-1 and takes them
/// (any order; an announcement naming another N or an id out of range ends the wait early so
/// that merge_announcements can name the offender). Throws RunFailure on a stop, or on the
/// timeout naming the agents still missing and those present.
std::vector<wire::AgentAnnouncement> await_announcements(transport::CoordinatorSession& session,
                                                         std::uint32_t num_agents,
                                                         const std::string& run_id,
                                                         double timeout_s);

}  // namespace tessera::coordinator
