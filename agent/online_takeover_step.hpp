#pragma once
// The take-over after a member of an online run was lost (--on-agent-loss continue,
// docs/online.md "Lost agents"): the survivors vote (agent/takeover_vote.hpp), reach the same
// graph and estimate, and move the lost blocks to their adopters. The agent's own bookkeeping
// (epochs, members, queues) is reset by its state machine (agent/online_agent.cpp,
// runtime/online_membership.hpp).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <set>
#include <vector>

#include "agent/takeover_vote.hpp"
#include "json_writer.hpp"
#include "runtime/online_agent_view.hpp"
#include "transport/online_channel.hpp"

namespace tessera::agent {

/// Thrown out of a wait when a member was lost (or a survivor voted so) and the run goes on
/// without it: the epoch is abandoned and the survivors agree on the take-over.
struct TakeoverNeeded {};

struct TakeoverStepResult {
  TakeoverVoteOutcome vote;
  runtime::TakeoverMoves moves;
};

/// Holds the vote among `members` (`take_votes` as in hold_takeover_vote), makes `view` hold
/// the graph every survivor holds (`wait_to_hold` returns once this agent received those
/// batches), applies the survivors' block poses and moves the lost blocks. Throws
/// transport::TransportError as hold_takeover_vote does.
TakeoverStepResult takeover_step(
    transport::OnlineChannel& channel, runtime::OnlineAgentView& view,
    const std::set<std::uint32_t>& members, const OwnVote& mine, double timeout_s,
    const std::function<std::vector<transport::OnlineReportSample>()>& take_votes,
    const std::function<void(const Watermarks&)>& wait_to_hold);

/// The summary's `faults` entry of a take-over: `noticed_at_s` and `taken_over_at_s` are the
/// run's clock when the loss was noticed and when the blocks had moved; `epoch` the one the
/// run goes on at.
cli::JsonObject lost_for_good_fault(const TakeoverStepResult& step, double noticed_at_s,
                                    double taken_over_at_s, std::uint32_t epoch,
                                    std::size_t total_poses);

}  // namespace tessera::agent
