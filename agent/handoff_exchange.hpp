#pragma once
// Step 6 of a fresh run on the agent's side: the hand-off, peer to peer. Every agent sends
// every other agent exactly one message with the measurements and initial poses of its
// share that the other now owns (the coordinator never sees measurement values), and waits
// for one from each of them.

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/local_share.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// Publishes `share`'s hand-off to every agent but `self` under `owner`, then waits up to
/// `timeout_s` for a hand-off from each of them. Returns them decoded, in arrival order.
/// Throws RunFailure on a stop or the timeout (naming the agents not heard from).
std::vector<ReceivedHandoff> exchange_handoffs(transport::AgentSession& session,
                                               const RobotShare& share,
                                               const std::vector<std::uint32_t>& owner,
                                               std::uint32_t self, std::uint32_t robots,
                                               const std::string& run_id, double timeout_s);

}  // namespace tessera::agent
