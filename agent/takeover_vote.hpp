#pragma once
// The survivors' vote after a member of an online run was lost (docs/online.md, "Lost
// agents"): each survivor sends its vote on the report topic (epoch kTakeoverEpoch) and reads
// the others' until runtime::TakeoverAgreement is complete, voting again whenever it learns of
// more lost members. The DDS side of the agreement; agent/online_takeover_step.cpp acts on the
// outcome.

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <tessera/online/absorb_gate.hpp>
#include <vector>

#include "transport/online_channel.hpp"
#include "transport/transport_error.hpp"

namespace tessera::agent {

/// What this agent votes with besides the lost set: where it was and what it holds.
struct OwnVote {
  std::uint32_t me = 0;
  std::uint32_t epoch = 0;  ///< The epoch the loss interrupted.
  Watermarks entered;       ///< Batches per robot in its graph.
  int rank = 0, dim = 0;    ///< Of its block's poses (dim 0: none yet).
  std::vector<std::uint32_t> pose_ids;
  std::vector<double> data;
};

struct TakeoverVoteOutcome {
  std::set<std::uint32_t> lost, survivors;
  std::uint32_t next_epoch = 0;  ///< One past the newest epoch a survivor voted from.
  Watermarks entered;            ///< The graph every survivor must hold (element-wise maximum).
  std::map<std::uint32_t, transport::OnlineReportSample> votes;  ///< Survivors' latest votes.
  std::size_t bytes_sent = 0;
};

/// The failure of agent `me` when a take-over vote counts it as lost (its liveliness lapsed
/// while it was alive, or it started again with the id of an agent taken over).
transport::TransportError counted_lost_error(std::uint32_t me);

/// Holds the vote among `members`. `take_votes` pumps the channel (and the stream) and returns
/// the take-over votes that arrived since its last call. Throws transport::TransportError when
/// a vote counts this agent as lost, or when a survivor's vote is still missing after
/// `timeout_s` seconds without progress.
TakeoverVoteOutcome hold_takeover_vote(
    transport::OnlineChannel& channel, const std::set<std::uint32_t>& members, const OwnVote& mine,
    double timeout_s,
    const std::function<std::vector<transport::OnlineReportSample>()>& take_votes);

}  // namespace tessera::agent
