#include "agent/online_link.hpp"

#include <algorithm>
#include <cstdio>
#include <tessera/util/input_error.hpp>
#include <utility>

#include "agent/online_estimate_publication.hpp"
#include "agent/online_takeover_step.hpp"
#include "agent/takeover_vote.hpp"
#include "rebalance_args.hpp"
#include "run_wide_args.hpp"
#include "step_coarse_args.hpp"
#include "transport/fastdds/shm_receive_watch.hpp"
#include "transport/transport_error.hpp"

namespace tessera::agent {

namespace {

// The options every agent of the run must share, as this agent's reports carry them.
transport::OnlineTeamOptions team_options(const OnlineOptions& o) {
  transport::OnlineTeamOptions t;
  t.rebalance = o.rebalance;
  t.step_coarse = o.newton_coarse;
  t.step_coarse_min_blocks = o.newton_coarse_min_blocks;
  t.step_coarse_aggregates = o.newton_coarse_aggregates;
  t.run_wide = cli::run_wide_options_of(o);
  return t;
}

// "" when `theirs` (agent `sender`'s report) equals `mine`; else the first option that differs.
std::string team_disagreement(const transport::OnlineTeamOptions& mine,
                              const transport::OnlineTeamOptions& theirs, unsigned sender) {
  std::string differs = cli::rebalance_disagreement(mine.rebalance, theirs.rebalance, sender);
  if (differs.empty())
    differs = cli::step_coarse_disagreement(
        mine.step_coarse, mine.step_coarse_min_blocks, mine.step_coarse_aggregates,
        theirs.step_coarse, theirs.step_coarse_min_blocks, theirs.step_coarse_aggregates, sender);
  if (differs.empty()) differs = cli::run_wide_disagreement(mine.run_wide, theirs.run_wide, sender);
  return differs;
}

double since(OnlineClock::time_point t) {
  return std::chrono::duration<double>(OnlineClock::now() - t).count();
}

}  // namespace

OnlineLink::OnlineLink(OnlineAgentState& state)
    : s_(state),
      stream_(state.o.domain, state.o.run_id),
      channel_(state.o.domain, state.o.run_id, state.me(),
               static_cast<std::uint32_t>(state.o.robots), state.o.lease_s,
               team_options(state.o.online)) {}

[[noreturn]] void OnlineLink::silent_peer(const std::string& what) const {
  const std::string stuck = transport::shm_receive_note();
  throw transport::TransportError("online agent " + std::to_string(s_.o.id) + ": " + what +
                                  " for " + std::to_string(s_.o.timeout_s) + " s (--timeout)" +
                                  (stuck.empty() ? std::string() : " (" + stuck + ")"));
}

void OnlineLink::pump_stream() {
  for (const auto& r : stream_.take(0.0)) {
    s_.arrivals.arrived(r.batch.robot, r.batch.sequence, s_.now_s());
    s_.view.receive(r.batch, r.dim, r.last);
  }
}

void OnlineLink::pump_channel() {
  for (auto& r : channel_.take_reports()) file_report(std::move(r));
  for (auto& m : channel_.take_messages())
    if (m.epoch >= s_.epoch) pending_.push(std::move(m));
}

void OnlineLink::file_report(transport::OnlineReportSample&& r) {
  // Every agent moves the blocks itself and takes part in every message step of the Newton
  // steps' coarse correction, so all use the lead's re-partition and --step-coarse options
  // (and its run-wide solver options, cli/run_wide_args.hpp: the local rounds decide who sends
  // each round): an agent whose options differ is not admitted (its hello is not counted), and an
  // agent that reads the lead's report with other options than its own stops, naming the option.
  const std::string differs = team_disagreement(team_options(s_.o.online), r.team, r.sender);
  if (r.epoch == transport::kHelloEpoch && !differs.empty()) {
    // Said as the joiner reads it: its values against the team's (the lead's, which every
    // member shares).
    if (refused_.insert(r.sender).second)
      std::fprintf(
          stderr, "agent %d: agent %u not admitted: its options differ (%s)\n", s_.o.id, r.sender,
          team_disagreement(r.team, team_options(s_.o.online), s_.membership.lead_of(s_.epoch))
              .c_str());
    return;
  }
  s_.membership.heard_from(r.sender);
  if (r.epoch == transport::kHelloEpoch) return;
  if (r.epoch == transport::kTakeoverEpoch) {
    // Counted lost: a live member whose lease lapsed, or a process started again with the
    // id of an agent whose block was taken over (the votes are kept for late readers).
    if (std::find(r.lost.begin(), r.lost.end(), s_.me()) != r.lost.end())
      throw counted_lost_error(s_.me());
    // Votes about losses already taken over are late copies.
    if (std::any_of(r.lost.begin(), r.lost.end(),
                    [&](std::uint32_t a) { return !s_.membership.lost(a); }))
      votes_.push_back(std::move(r));
    return;
  }
  if (s_.membership.abandoned(r.epoch)) return;  // an epoch abandoned at a take-over
  if (r.sender == s_.membership.lead_of(r.epoch)) {
    if (!differs.empty()) throw InputError(differs);
    s_.membership.admit(r.epoch, r.next_members);
  }
  if (r.epoch >= s_.epoch) reports_[r.epoch][r.sender] = std::move(r);
}

void OnlineLink::check_losses() {
  if (!s_.o.continue_on_loss || !s_.member()) return;
  if (!votes_.empty()) throw TakeoverNeeded{};
  for (std::uint32_t a : channel_.lost_agents())
    if (s_.members().count(a) > 0 && a != s_.me()) throw TakeoverNeeded{};
}

void OnlineLink::send_report(const transport::OnlineReportSample& report) {
  s_.fig.report_bytes += channel_.send_report(report);
}

std::vector<transport::OnlineReportSample> OnlineLink::take_votes() {
  std::vector<transport::OnlineReportSample> v;
  v.swap(votes_);
  return v;
}

void OnlineLink::drop_before(std::uint32_t epoch) {
  for (auto it = reports_.begin(); it != reports_.end();)
    it = it->first < epoch ? reports_.erase(it) : std::next(it);
  pending_.drop_before(epoch);
}

void OnlineLink::wait_matched() {
  const auto peers = static_cast<int>(s_.members().size());
  const auto start = OnlineClock::now();
  while (channel_.matched_peers() < peers) {
    check_losses();
    if (since(start) > s_.o.timeout_s) silent_peer("peers not all matched");
    channel_.wait(0.01);
    pump_channel();
    pump_stream();
  }
}

void OnlineLink::wait_for_reports() {
  const auto complete = [&] {
    const auto& have = reports_[s_.epoch];
    for (std::uint32_t m : s_.members())
      if (have.count(m) == 0) return false;
    return true;
  };
  // The timeout runs once the epoch began (some report of it arrived): a joiner may wait for
  // the next epoch as long as the members idle.
  auto last_progress = OnlineClock::now();
  std::size_t have = 0;
  while (!complete()) {
    channel_.wait(0.05);
    pump_channel();
    pump_stream();
    // A member that finished the run leaves after its last report arrived: only a report
    // still missing after the pump makes its absence a loss.
    if (complete()) break;
    check_losses();
    if (reports_[s_.epoch].size() != have) {
      have = reports_[s_.epoch].size();
      last_progress = OnlineClock::now();
    } else if (have > 0 && since(last_progress) > s_.o.timeout_s) {
      std::string missing;
      for (std::uint32_t m : s_.members())
        if (reports_[s_.epoch].count(m) == 0)
          missing += (missing.empty() ? "" : ",") + std::to_string(m);
      silent_peer("no epoch " + std::to_string(s_.epoch) + " report from agent " + missing);
    }
  }
}

void OnlineLink::wait_to_hold(const Watermarks& decision, bool read_channel) {
  // With `read_channel` (an epoch's step) the channel is read here too: a process started again
  // with a lost agent's id follows the epochs it missed and may wait here for stream data
  // first, and only the kept take-over votes tell it that it was counted lost (pump_channel
  // throws then). Not inside a take-over, whose own vote reads the channel: a vote buffered
  // here before the lost agents are marked dead would start a second take-over. Either way the
  // wait ends after --timeout seconds without a new batch rather than never.
  auto last_progress = OnlineClock::now();
  std::size_t held_before = 0;
  for (;;) {
    bool have_all = true;
    const Watermarks mine = s_.view.held();
    std::size_t held = 0;
    for (const auto& [robot, count] : mine) held += count;
    for (const auto& [robot, count] : decision) {
      auto it = mine.find(robot);
      if (count > (it == mine.end() ? 0 : it->second)) have_all = false;
    }
    if (have_all) return;
    if (held != held_before) {
      held_before = held;
      last_progress = OnlineClock::now();
    } else if (since(last_progress) > s_.o.timeout_s) {
      silent_peer("no new stream batch while waiting for the data of epoch " +
                  std::to_string(s_.epoch));
    }
    pump_stream();
    if (read_channel) pump_channel();
    channel_.wait(0.01);
  }
}

void OnlineLink::wait_for_news(const Watermarks& decision) {
  for (;;) {
    pump_stream();
    pump_channel();
    check_losses();
    bool more = false;
    for (const auto& [robot, count] : s_.view.held()) {
      auto it = decision.find(robot);
      if (s_.membership.absorbs(robot, s_.epoch) && count > (it == decision.end() ? 0 : it->second))
        more = true;
    }
    const bool joiner = s_.lead() && s_.membership.joiner_waiting(s_.epoch);
    if (more || joiner || reports_.count(s_.epoch + 1) > 0) return;
    channel_.wait(0.05);
  }
}

void OnlineLink::send(const std::vector<OutgoingMessage>& out) {
  for (const auto& m : out) {
    s_.fig.bytes_sent += channel_.send(m, s_.epoch);
    ++s_.fig.messages_sent;
  }
}

void OnlineLink::run_rounds(CertifiedAgent& agent, std::uint32_t me) {
  send(agent.start());
  auto last_message = OnlineClock::now();
  while (!agent.done()) {
    const bool handled = pending_.take(
        s_.epoch, me,
        [&](const transport::OnlineProtocolSample& m) { send(agent.handle(m.message)); },
        [&] { return agent.done(); });
    if (agent.done()) break;
    if (handled) {
      last_message = OnlineClock::now();
      continue;
    }
    check_losses();
    channel_.wait(0.02);
    pump_channel();
    pump_stream();
    if (since(last_message) > s_.o.timeout_s) {
      // Name the agents whose messages the protocol still waits for (block -> robot = agent).
      std::string missing;
      if (const auto awaited = agent.awaited())
        for (std::uint32_t b : awaited->senders)
          if (const long robot = s_.block.robot_of_block(s_.view, b); robot >= 0)
            missing += (missing.empty() ? " from agent " : ",") + std::to_string(robot);
      silent_peer("no protocol message" + missing);
    }
  }
}

void OnlineLink::publish_estimate() {
  s_.last_publish_s = s_.now_s();
  if (publish_online_estimate(s_.view, channel_, s_.epoch, s_.me(), s_.o.tum_dir))
    ++s_.fig.publications;
}

}  // namespace tessera::agent
