#pragma once
// Step 6 of a fresh run on the agent's side: the hand-off, peer to peer. Every agent sends
// every other agent exactly one hand-off with the measurements and initial poses of its
// share that the other now owns (the coordinator never sees measurement values), and waits
// for one from each of them. A hand-off travels in parts of one transport message each, on a
// topic filtered by recipient (transport/addressed_filter.hpp), so that an agent receives only
// its own: at a million poses over 25 agents, every agent receiving every hand-off (the whole
// graph's measurements that change owner, 24 times over) stalled the shared-memory transport.

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/local_share.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// What sending a hand-off took (for the agent's log).
struct HandoffSending {
  std::size_t parts = 0;    ///< Parts written, to every peer together.
  double send_s = 0.0;      ///< Planning and writing every part, waits included.
  double ack_wait_s = 0.0;  ///< Of which waiting for parts to be acknowledged.
};

/// Publishes `share`'s hand-off to every agent but `self` under `owner`, then waits up to
/// `timeout_s` for every part of a hand-off from each of them. Returns them decoded, one per
/// sender (its parts joined in order), by sender id.
/// Throws RunFailure on a stop or the timeout (naming the agents not heard from).
/// `sending`, when given, receives what sending took.
std::vector<ReceivedHandoff> exchange_handoffs(transport::AgentSession& session,
                                               const RobotShare& share,
                                               const std::vector<std::uint32_t>& owner,
                                               std::uint32_t self, std::uint32_t robots,
                                               const std::string& run_id, double timeout_s,
                                               HandoffSending* sending = nullptr);

}  // namespace tessera::agent
