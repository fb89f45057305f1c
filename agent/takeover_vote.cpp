#include "agent/takeover_vote.hpp"

#include <chrono>
#include <string>
#include <utility>

#include "runtime/takeover_agreement.hpp"

namespace tessera::agent {

transport::TransportError counted_lost_error(std::uint32_t me) {
  return transport::TransportError(
      "online agent " + std::to_string(me) +
      " was counted as lost by the survivors (its liveliness lapsed): its block was taken over "
      "and the run goes on without it");
}

TakeoverVoteOutcome hold_takeover_vote(
    transport::OnlineChannel& channel, const std::set<std::uint32_t>& members, const OwnVote& mine,
    double timeout_s,
    const std::function<std::vector<transport::OnlineReportSample>()>& take_votes) {
  using Clock = std::chrono::steady_clock;
  runtime::TakeoverAgreement agreement(members, mine.me);
  TakeoverVoteOutcome out;
  auto count = [&](transport::OnlineReportSample v) {
    runtime::TakeoverVote t;
    t.sender = v.sender;
    t.lost = std::set<std::uint32_t>(v.lost.begin(), v.lost.end());
    t.at_epoch = v.at_epoch;
    t.entered = v.held;
    const bool grew = agreement.vote(t);
    out.votes[v.sender] = std::move(v);
    return grew;
  };
  // Returns whether the lost set grew (this agent must vote again).
  auto read = [&] {
    bool grew = false;
    for (auto& v : take_votes()) grew = count(std::move(v)) || grew;
    const auto seen = channel.lost_agents();
    grew = agreement.suspect(std::set<std::uint32_t>(seen.begin(), seen.end())) || grew;
    if (agreement.counts_me_lost()) throw counted_lost_error(mine.me);
    return grew;
  };
  read();
  auto last_progress = Clock::now();
  for (bool vote = true;; vote = read()) {
    if (vote) {
      transport::OnlineReportSample v;
      v.epoch = transport::kTakeoverEpoch;
      v.sender = mine.me;
      v.held = mine.entered;
      v.rank = mine.rank;
      v.dim = mine.dim;
      v.pose_ids = mine.pose_ids;
      v.data = mine.data;
      v.lost.assign(agreement.lost().begin(), agreement.lost().end());
      v.at_epoch = mine.epoch;
      out.bytes_sent += channel.send_report(v);
      count(std::move(v));
      last_progress = Clock::now();
    }
    if (agreement.complete()) break;
    if (std::chrono::duration<double>(Clock::now() - last_progress).count() > timeout_s) {
      std::string missing;
      for (std::uint32_t a : agreement.survivors()) {
        auto it = out.votes.find(a);
        const std::set<std::uint32_t> named =
            it == out.votes.end()
                ? std::set<std::uint32_t>{}
                : std::set<std::uint32_t>(it->second.lost.begin(), it->second.lost.end());
        if (named != agreement.lost()) missing += (missing.empty() ? "" : ",") + std::to_string(a);
      }
      throw transport::TransportError("online agent " + std::to_string(mine.me) +
                                      ": no take-over vote from agent " + missing + " for " +
                                      std::to_string(timeout_s) + " s (--timeout)");
    }
    channel.wait(0.05);
  }
  out.lost = agreement.lost();
  out.survivors = agreement.survivors();
  out.next_epoch = agreement.next_epoch();
  out.entered = agreement.entered();
  for (auto it = out.votes.begin(); it != out.votes.end();)
    it = out.survivors.count(it->first) > 0 ? std::next(it) : out.votes.erase(it);
  return out;
}

}  // namespace tessera::agent
