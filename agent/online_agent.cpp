#include "agent/online_agent.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <tessera/certification/rounding_gap.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

#include "agent/online_agent_options.hpp"
#include "agent/online_agent_summary.hpp"
#include "agent/online_batch_arrivals.hpp"
#include "agent/online_block_solver.hpp"
#include "agent/online_estimate_publication.hpp"
#include "agent/online_solve_outcome.hpp"
#include "agent/online_takeover_step.hpp"
#include "agent/takeover_vote.hpp"
#include "json_writer.hpp"
#include "rebalance_args.hpp"
#include "runtime/online_agent_view.hpp"
#include "step_coarse_args.hpp"
#include "transport/fastdds/shm_receive_watch.hpp"
#include "transport/fastdds/teardown_guard.hpp"
#include "transport/graph_stream_topic.hpp"
#include "transport/online_channel.hpp"
#include "transport/transport_error.hpp"

namespace tessera::agent {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

double cpu_now() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

// The options every agent of the run must share, as this agent's reports carry them.
transport::OnlineTeamOptions team_options(const OnlineOptions& o) {
  transport::OnlineTeamOptions t;
  t.rebalance = o.rebalance;
  t.step_coarse = o.newton_coarse;
  t.step_coarse_min_blocks = o.newton_coarse_min_blocks;
  return t;
}

// "" when `theirs` (agent `sender`'s report) equals `mine`; else the first option that differs.
std::string team_disagreement(const transport::OnlineTeamOptions& mine,
                              const transport::OnlineTeamOptions& theirs, unsigned sender) {
  std::string differs = cli::rebalance_disagreement(mine.rebalance, theirs.rebalance, sender);
  if (differs.empty())
    differs =
        cli::step_coarse_disagreement(mine.step_coarse, mine.step_coarse_min_blocks,
                                      theirs.step_coarse, theirs.step_coarse_min_blocks, sender);
  return differs;
}

class OnlineAgent {
 public:
  explicit OnlineAgent(const OnlineAgentOptions& o)
      : o_(o),
        view_(o.id, o.robots, o.online),
        stream_(o.domain, o.run_id),
        channel_(o.domain, o.run_id, static_cast<std::uint32_t>(o.id),
                 static_cast<std::uint32_t>(o.robots), o.lease_s, team_options(o.online)),
        start_(Clock::now()),
        block_(o.online) {}

  int run();

 private:
  void pump_stream();
  void pump_channel();
  void wait_for_reports();
  bool reports_complete();
  void wait_matched(std::size_t peers);
  /// The agents that take part in the current epoch (the lead's previous report says so).
  const std::set<std::uint32_t>& members() const;
  /// The member that admits joiners, asks for certificates and writes the answer: the lowest
  /// member of `epoch` (agent 0 unless it was lost).
  std::uint32_t lead_of(std::uint32_t epoch) const;
  /// Throws TakeoverNeeded when --on-agent-loss continue and a member was lost.
  void check_losses();
  /// The survivors agree on what was lost, reach the same graph and move the lost blocks.
  void take_over();
  SolveOutcome solve(bool certify, bool climb = true);
  /// The round protocol of the epoch's solve, until `agent` is done.
  void solve_rounds(CertifiedAgent& agent, std::uint32_t me);
  /// One epoch: report, agree, enter, solve or idle. Returns false once the run is over.
  bool epoch_step();
  /// Whether `robot`'s batches may enter: its agent is a member, or it was lost and its
  /// block's adopter absorbs them.
  bool absorbs(std::uint32_t robot) const;
  void wait_to_hold(const Watermarks& decision, bool read_channel);
  void publish_estimate();
  /// Batches entered per robot 0..robots-1 (the epoch's absorption watermarks).
  std::vector<std::size_t> entered_per_robot() const;
  void send(const std::vector<OutgoingMessage>& out, std::uint32_t epoch);
  void write_json(bool lead_result);
  [[noreturn]] void silent_peer(const std::string& what) const;

  OnlineAgentOptions o_;
  runtime::OnlineAgentView view_;
  transport::GraphStreamReader stream_;
  transport::OnlineChannel channel_;
  Clock::time_point start_;
  std::uint32_t epoch_ = 0;
  bool converged_ = true;
  OnlineBlockSolver block_;  // this agent's block, grown from solve to solve
  std::map<std::uint32_t, std::map<std::uint32_t, transport::OnlineReportSample>> reports_;
  std::map<std::uint32_t, std::set<std::uint32_t>> members_{{0, {0}}};
  std::set<std::uint32_t> seen_;     // agents heard from (hello or report)
  std::set<std::uint32_t> dead_;     // members lost and taken over
  std::set<std::uint32_t> refused_;  // hellos with other re-partition options (not admitted)
  std::uint32_t floor_ = 0;          // reports of epochs below it belong to an abandoned epoch
  std::vector<transport::OnlineReportSample> votes_;  // take-over votes not yet read
  bool finishing_ = false;
  double next_certificate_ = 0.0, last_publish_ = -1e300;
  bool changed_since_certificate_ = false;
  std::vector<transport::OnlineProtocolSample> pending_;
  BatchArrivals arrivals_;
  OnlineFigures fig_;
  SolveOutcome final_;
  double cost_ = 0.0;
  double last_grad_norm_ = 0.0;
  bool have_cost_ = false;
};

[[noreturn]] void OnlineAgent::silent_peer(const std::string& what) const {
  const std::string stuck = transport::shm_receive_note();
  throw transport::TransportError("online agent " + std::to_string(o_.id) + ": " + what + " for " +
                                  std::to_string(o_.timeout_s) + " s (--timeout)" +
                                  (stuck.empty() ? std::string() : " (" + stuck + ")"));
}

void OnlineAgent::pump_stream() {
  for (const auto& r : stream_.take(0.0)) {
    arrivals_.arrived(r.batch.robot, r.batch.sequence, since(start_));
    view_.receive(r.batch, r.dim, r.last);
  }
}

void OnlineAgent::pump_channel() {
  for (auto& r : channel_.take_reports()) {
    // Every agent moves the blocks itself and takes part in every message step of the Newton
    // steps' coarse correction, so all use the lead's re-partition and --step-coarse options:
    // an agent whose options differ is not admitted (its hello is not counted), and an agent
    // that reads the lead's report with other options than its own stops, naming the option.
    const std::string differs = team_disagreement(team_options(o_.online), r.team, r.sender);
    if (r.epoch == transport::kHelloEpoch && !differs.empty()) {
      if (refused_.insert(r.sender).second)
        std::fprintf(stderr, "agent %d: agent %u not admitted: its options differ (%s)\n", o_.id,
                     r.sender, differs.c_str());
      continue;
    }
    if (r.sender < static_cast<std::uint32_t>(o_.robots) && dead_.count(r.sender) == 0)
      seen_.insert(r.sender);
    if (r.epoch == transport::kHelloEpoch) continue;
    if (r.epoch == transport::kTakeoverEpoch) {
      // Counted lost: a live member whose lease lapsed, or a process started again with the
      // id of an agent whose block was taken over (the votes are kept for late readers).
      if (std::find(r.lost.begin(), r.lost.end(), static_cast<std::uint32_t>(o_.id)) !=
          r.lost.end())
        throw counted_lost_error(static_cast<std::uint32_t>(o_.id));
      // Votes about losses already taken over are late copies.
      if (std::any_of(r.lost.begin(), r.lost.end(),
                      [&](std::uint32_t a) { return dead_.count(a) == 0; }))
        votes_.push_back(std::move(r));
      continue;
    }
    if (r.epoch < floor_) continue;  // an epoch abandoned at a take-over
    if (r.sender == lead_of(r.epoch)) {
      if (!differs.empty()) throw InputError(differs);
      members_[r.epoch + 1] = std::set<std::uint32_t>(r.next_members.begin(), r.next_members.end());
    }
    if (r.epoch >= epoch_) reports_[r.epoch][r.sender] = std::move(r);
  }
  for (auto& m : channel_.take_messages())
    if (m.epoch >= epoch_) pending_.push_back(std::move(m));
}

const std::set<std::uint32_t>& OnlineAgent::members() const {
  return members_.at(epoch_);
}

std::uint32_t OnlineAgent::lead_of(std::uint32_t epoch) const {
  auto it = members_.find(epoch);
  return it == members_.end() || it->second.empty() ? 0 : *it->second.begin();
}

void OnlineAgent::check_losses() {
  if (!o_.continue_on_loss || members().count(static_cast<std::uint32_t>(o_.id)) == 0) return;
  if (!votes_.empty()) throw TakeoverNeeded{};
  for (std::uint32_t a : channel_.lost_agents())
    if (members().count(a) > 0 && a != static_cast<std::uint32_t>(o_.id)) throw TakeoverNeeded{};
}

bool OnlineAgent::reports_complete() {
  const auto& have = reports_[epoch_];
  for (std::uint32_t m : members())
    if (have.count(m) == 0) return false;
  return true;
}

void OnlineAgent::wait_for_reports() {
  // The timeout runs once the epoch began (some report of it arrived): a joiner may wait for
  // the next epoch as long as the members idle.
  auto last_progress = Clock::now();
  std::size_t have = 0;
  while (!reports_complete()) {
    channel_.wait(0.05);
    pump_channel();
    pump_stream();
    // A member that finished the run leaves after its last report arrived: only a report
    // still missing after the pump makes its absence a loss.
    if (reports_complete()) break;
    check_losses();
    if (reports_[epoch_].size() != have) {
      have = reports_[epoch_].size();
      last_progress = Clock::now();
    } else if (have > 0 && since(last_progress) > o_.timeout_s) {
      std::string missing;
      for (std::uint32_t m : members())
        if (reports_[epoch_].count(m) == 0)
          missing += (missing.empty() ? "" : ",") + std::to_string(m);
      silent_peer("no epoch " + std::to_string(epoch_) + " report from agent " + missing);
    }
  }
}

void OnlineAgent::wait_matched(std::size_t peers) {
  const auto start = Clock::now();
  while (channel_.matched_peers() < static_cast<int>(peers)) {
    check_losses();
    if (since(start) > o_.timeout_s) silent_peer("peers not all matched");
    channel_.wait(0.01);
    pump_channel();
    pump_stream();
  }
}

void OnlineAgent::send(const std::vector<OutgoingMessage>& out, std::uint32_t epoch) {
  for (const auto& m : out) {
    fig_.bytes_sent += channel_.send(m, epoch);
    ++fig_.messages_sent;
  }
}

SolveOutcome OnlineAgent::solve(bool certify, bool climb) {
  return block_.solve(view_, certify, climb,
                      [&](CertifiedAgent& agent, std::uint32_t me) { solve_rounds(agent, me); });
}

void OnlineAgent::solve_rounds(CertifiedAgent& agent, std::uint32_t me) {
  send(agent.start(), epoch_);
  auto last_message = Clock::now();
  while (!agent.done()) {
    bool handled = false;
    // One pass over the queue, compacting it in place (no erase from its middle per message):
    // this epoch's messages for this agent are handled in arrival order, later epochs' wait for
    // their solve, older epochs' leftovers and messages for others go. Once the solve is done,
    // the rest stays queued as it is.
    std::size_t keep = 0, k = 0;
    for (; k < pending_.size() && !agent.done(); ++k) {
      auto& m = pending_[k];
      const bool mine = m.epoch == epoch_ && m.sender != me &&
                        (m.broadcast || std::find(m.recipients.begin(), m.recipients.end(), me) !=
                                            m.recipients.end());
      if (mine) {
        send(agent.handle(m.message), epoch_);
        handled = true;
      } else if (m.epoch > epoch_) {
        if (keep != k) pending_[keep] = std::move(m);
        ++keep;
      }
    }
    for (; k < pending_.size(); ++k, ++keep)
      if (keep != k) pending_[keep] = std::move(pending_[k]);
    pending_.erase(pending_.begin() + static_cast<std::ptrdiff_t>(keep), pending_.end());
    if (agent.done()) break;
    if (handled) {
      last_message = Clock::now();
      continue;
    }
    check_losses();
    channel_.wait(0.02);
    pump_channel();
    pump_stream();
    if (since(last_message) > o_.timeout_s) {
      // Name the agents whose messages the protocol still waits for (block -> robot = agent).
      std::string missing;
      if (const auto awaited = agent.awaited())
        for (std::uint32_t b : awaited->senders)
          if (const long robot = block_.robot_of_block(view_, b); robot >= 0)
            missing += (missing.empty() ? " from agent " : ",") + std::to_string(robot);
      silent_peer("no protocol message" + missing);
    }
  }
}

void OnlineAgent::publish_estimate() {
  last_publish_ = since(start_);
  if (publish_online_estimate(view_, channel_, epoch_, static_cast<std::uint32_t>(o_.id),
                              o_.tum_dir))
    ++fig_.publications;
}

int OnlineAgent::run() {
  const auto me = static_cast<std::uint32_t>(o_.id);
  // Membership: agent 0 starts alone (epoch 0) and admits every agent it has heard from at
  // the next epoch boundary (its report's next_members), so the run needs no start barrier
  // and an agent started late is taken in the same way. A joiner first follows the epochs it
  // missed from the reports (kept for late readers): the same entered batches and block
  // poses give it the members' graph and estimate.
  if (me != 0) {
    transport::OnlineReportSample hello;
    hello.epoch = transport::kHelloEpoch;
    hello.sender = me;
    fig_.report_bytes += channel_.send_report(hello);
  }
  for (;;) {
    try {
      if (!epoch_step()) break;
    } catch (const TakeoverNeeded&) {
      take_over();
    }
  }
  // The lead rounds the whole estimate (every block's poses arrived with the last reports).
  const bool lead = me == lead_of(epoch_);
  if (lead) {
    const PoseGraph& graph = view_.stream()->graph();
    if (graph.num_poses > 0 && count_components(graph) == 1) {
      const std::vector<Pose> poses = round_solution(graph, view_.iterate());
      cost_ = evaluate_objective(graph, poses);
      have_cost_ = true;
      if (final_.relaxation_cost)
        final_.certified = estimate_certified(final_.certified, cost_, *final_.relaxation_cost);
    }
  }
  channel_.flush(5.0);
  if (!o_.json.empty()) write_json(lead);
  return 0;
}

bool OnlineAgent::epoch_step() {
  const auto me = static_cast<std::uint32_t>(o_.id);
  pump_stream();
  pump_channel();
  const bool member = members().count(me) > 0;
  if (member) {
    wait_matched(members().size());
    transport::OnlineReportSample mine;
    mine.epoch = epoch_;
    mine.sender = me;
    mine.held = view_.held();
    mine.converged = converged_;
    mine.rank = block_.own_rank();
    mine.dim = view_.dim();
    mine.pose_ids = block_.own_ids();
    mine.data = block_.own_data();
    if (me == lead_of(epoch_)) {
      if (o_.certify_every_s > 0 && changed_since_certificate_ &&
          since(start_) >= next_certificate_) {
        mine.certify = true;
        next_certificate_ = since(start_) + o_.certify_every_s;
        changed_since_certificate_ = false;
      }
      std::set<std::uint32_t> next = members();
      next.insert(seen_.begin(), seen_.end());
      // An agent that said hello and died before it was admitted is not admitted.
      if (o_.continue_on_loss)
        for (std::uint32_t a : channel_.lost_agents())
          if (members().count(a) == 0) next.erase(a);
      mine.next_members.assign(next.begin(), next.end());
    }
    fig_.report_bytes += channel_.send_report(mine);
  }
  wait_for_reports();
  std::vector<Watermarks> held;
  bool all_converged = true;
  for (const auto& [sender, r] : reports_[epoch_]) {
    if (members().count(sender) == 0) continue;
    if (sender != me && r.dim != 0) {
      if (view_.dim() == 0) pump_stream();  // the block's graph must be there first
      view_.apply_block(r.pose_ids, r.data, r.rank);
    }
    held.push_back(r.held);
    all_converged = all_converged && r.converged;
  }
  converged_ = all_converged;
  const std::uint32_t lead = lead_of(epoch_);
  const bool certify_now = reports_[epoch_].count(lead) > 0 && reports_[epoch_][lead].certify;
  // The estimate is whole here (every block's poses of the last solve arrived).
  if (finishing_) {
    if (o_.publish_every_s > 0 || !o_.tum_dir.empty()) publish_estimate();
    return false;
  }
  if (o_.publish_every_s > 0 && since(start_) - last_publish_ >= o_.publish_every_s)
    publish_estimate();
  AbsorbGate gate;
  Watermarks decision = gate.decide(held);
  // Only the members' robots and those of lost agents (their blocks' adopters absorb them): a
  // robot's data waits for its agent.
  for (auto& [robot, count] : decision)
    if (!absorbs(robot)) count = 0;
  // The members hold what they decided; a joiner following missed epochs may not yet.
  wait_to_hold(decision, true);
  const double step_start = since(start_);
  const double cpu_start = cpu_now();
  const runtime::EnteredData in = view_.enter(decision);
  const bool changed = in.poses > 0 || in.measurements > 0;
  if (o_.verbose) {
    std::string who;
    for (std::uint32_t m : members()) who += " " + std::to_string(m);
    std::fprintf(stderr, "agent %d: epoch %u members%s: +%zu poses +%zu measurements%s%s\n", o_.id,
                 epoch_, who.c_str(), in.poses, in.measurements, member ? "" : " (following)",
                 converged_ ? " converged" : "");
  }
  reports_.erase(epoch_);
  if (view_.stream_over()) {
    if (member) final_ = solve(o_.online.certify_at_end);
    if (o_.verbose)
      std::fprintf(stderr, "agent %d: final solve: %d rounds, certified %s\n", o_.id, final_.rounds,
                   final_.certified.value_or(false) ? "yes" : "no");
    fig_.cpu_s += cpu_now() - cpu_start;
    finishing_ = true;
    ++epoch_;
    return true;
  }
  if (!member) {
    ++epoch_;
    return true;
  }
  if (changed) changed_since_certificate_ = true;
  if (certify_now && count_components(view_.stream()->graph()) == 1) {
    const SolveOutcome c = solve(true, false);
    converged_ = c.grad_norm <= o_.online.solver.grad_norm_tol || c.stop_reason == "stalled";
    fig_.cpu_s += cpu_now() - cpu_start;
    fig_.rounds += c.rounds;
    cli::JsonObject j;
    j.add("epoch", static_cast<long long>(epoch_))
        .add("time_s", step_start)
        .add("poses", view_.stream()->graph().num_poses)
        .add("certified", c.certified)
        .add("min_eigenvalue", c.min_eigenvalue)
        .add("rounds", c.rounds)
        .add("ms", 1000.0 * (since(start_) - step_start));
    fig_.certificates.push_back(std::move(j));
    ++epoch_;
    return true;
  }
  if (!changed && converged_) {
    // Idle: a blocking wait for new data (ours, another agent's next report, or a hello
    // for the lead to admit); nothing is sent meanwhile.
    ++fig_.idle_waits;
    for (;;) {
      pump_stream();
      pump_channel();
      check_losses();
      const Watermarks now = view_.held();
      bool more = false;
      for (const auto& [robot, count] : now) {
        auto it = decision.find(robot);
        if (absorbs(robot) && count > (it == decision.end() ? 0 : it->second)) more = true;
      }
      bool joiner = false;
      if (me == lead)
        for (std::uint32_t a : seen_) joiner = joiner || members().count(a) == 0;
      if (more || joiner || reports_.count(epoch_ + 1) > 0) break;
      channel_.wait(0.05);
    }
    ++epoch_;
    return true;
  }
  // Every new measurement only placed a new pose (odometry, mostly) and every member voted
  // converged in its report: each new measurement has zero residual at the composed poses,
  // so f and its gradient are what they were. Every member sees the same votes and the same
  // entered data, so all skip the solve together, without a message of their own; the new
  // poses join their blocks at the next solve.
  const bool unchanged = converged_ && in.composed == in.measurements;
  SolveOutcome s;
  if (unchanged) {
    s.stop_reason = "unchanged";
    s.grad_norm = last_grad_norm_;
  } else {
    s = solve(false);
    if (o_.verbose)
      std::fprintf(stderr, "agent %d: solve: %d rounds, gradient norm %g (%s)\n", o_.id, s.rounds,
                   s.grad_norm, s.stop_reason.c_str());
    converged_ = s.grad_norm <= o_.online.solver.grad_norm_tol || s.stop_reason == "stalled";
    last_grad_norm_ = s.grad_norm;
    ++fig_.solves;
  }
  const double step_end = since(start_);
  const double step_cpu = cpu_now() - cpu_start;
  fig_.cpu_s += step_cpu;
  fig_.rounds += s.rounds;
  const GraphStream& g = *view_.stream();
  const double oldest = arrivals_.absorbed(g, step_end, step_start, fig_.batch_latency_s, step_cpu,
                                           &fig_.batch_latency_cpu_s);
  cli::JsonObject u;
  u.add("epoch", static_cast<long long>(epoch_))
      .add("time_s", step_start)
      .add("batches", in.batches)
      .add("poses", in.poses)
      .add("measurements", in.measurements)
      .add("total_poses", g.graph().num_poses)
      .add("total_measurements", g.graph().measurements.size())
      .add("agents", static_cast<long long>(members().size()))
      .add("moved", in.moved)
      .add("largest_block", in.largest_block)
      .add("smallest_block", in.smallest_block)
      .add("cut", in.cut)
      .add("entered", entered_per_robot())
      .add("rounds", s.rounds)
      .add("newton_steps", s.newton_steps)
      .add("newton_cg_iterations", s.newton_cg_iterations)
      .add("newton_message_steps", s.newton_message_steps)
      .add("coarse_unknowns", s.coarse_unknowns)
      .add("ms", 1000.0 * (step_end - step_start))
      .add("latency_s", step_end - oldest)
      .add("cpu_s", step_cpu)
      .add("latency_cpu_s", step_start - oldest + step_cpu)
      .add("grad_norm", s.grad_norm)
      .add("stop_reason", s.stop_reason);
  fig_.updates.push_back(std::move(u));
  ++epoch_;
  return true;
}

std::vector<std::size_t> OnlineAgent::entered_per_robot() const {
  std::vector<std::size_t> out(static_cast<std::size_t>(o_.robots), 0);
  for (const auto& [robot, count] : view_.entered())
    if (robot < out.size()) out[robot] = static_cast<std::size_t>(count);
  return out;
}

bool OnlineAgent::absorbs(std::uint32_t robot) const {
  return members().count(robot) > 0 || dead_.count(robot) > 0;
}

void OnlineAgent::wait_to_hold(const Watermarks& decision, bool read_channel) {
  // With `read_channel` (an epoch's step) the channel is read here too: a process started again
  // with a lost agent's id follows the epochs it missed and may wait here for stream data
  // first, and only the kept take-over votes tell it that it was counted lost (pump_channel
  // throws then). Not inside a take-over, whose own vote reads the channel: a vote buffered
  // here before the lost agents are marked dead would start a second take-over. Either way the
  // wait ends after --timeout seconds without a new batch rather than never.
  auto last_progress = Clock::now();
  std::size_t held_before = 0;
  for (;;) {
    bool have_all = true;
    const Watermarks mine = view_.held();
    std::size_t held = 0;
    for (const auto& [robot, count] : mine) held += count;
    for (const auto& [robot, count] : decision) {
      auto it = mine.find(robot);
      if (count > (it == mine.end() ? 0 : it->second)) have_all = false;
    }
    if (have_all) return;
    if (held != held_before) {
      held_before = held;
      last_progress = Clock::now();
    } else if (since(last_progress) > o_.timeout_s) {
      silent_peer("no new stream batch while waiting for the data of epoch " +
                  std::to_string(epoch_));
    }
    pump_stream();
    if (read_channel) pump_channel();
    channel_.wait(0.01);
  }
}

void OnlineAgent::take_over() {
  const auto me = static_cast<std::uint32_t>(o_.id);
  const double at = since(start_);
  OwnVote mine;
  mine.me = me;
  mine.epoch = epoch_;
  mine.entered = view_.entered();
  mine.rank = block_.own_rank();
  mine.dim = view_.dim();
  mine.pose_ids = block_.own_ids();
  mine.data = block_.own_data();
  const TakeoverStepResult step = takeover_step(
      channel_, view_, members(), mine, o_.timeout_s,
      [&] {
        pump_channel();
        pump_stream();
        std::vector<transport::OnlineReportSample> v;
        v.swap(votes_);
        return v;
      },
      [&](const Watermarks& target) { wait_to_hold(target, false); });
  fig_.report_bytes += step.vote.bytes_sent;
  const std::set<std::uint32_t>& survivors = step.vote.survivors;
  dead_.insert(step.vote.lost.begin(), step.vote.lost.end());
  for (std::uint32_t a : dead_) seen_.erase(a);
  // The run goes on at an epoch no survivor has used: leftovers of the abandoned one (its
  // messages, reports, the lead's admissions) are dropped.
  epoch_ = step.vote.next_epoch;
  floor_ = epoch_;
  members_.erase(members_.begin(), members_.lower_bound(epoch_));
  members_[epoch_] = survivors;
  for (auto it = reports_.begin(); it != reports_.end();)
    it = it->first < epoch_ ? reports_.erase(it) : std::next(it);
  pending_.erase(std::remove_if(pending_.begin(), pending_.end(),
                                [&](const auto& m) { return m.epoch < epoch_; }),
                 pending_.end());
  converged_ = false;  // the blocks changed: solve again
  finishing_ = false;  // a final solve the loss interrupted runs again
  fig_.faults.push_back(
      lost_for_good_fault(step, at, since(start_), epoch_,
                          view_.stream() ? view_.stream()->graph().num_poses : std::size_t{0}));
  if (o_.verbose)
    std::fprintf(stderr,
                 "agent %d: took over the blocks of %zu lost agent(s): %zu poses moved, epoch %u\n",
                 o_.id, step.vote.lost.size(), step.moves.moved, epoch_);
}

void OnlineAgent::write_json(bool lead_result) {
  OnlineSummaryState state;
  state.epochs = epoch_;
  state.graph = view_.stream();
  state.final_solve = final_;
  state.wall_s = since(start_);
  if (lead_result && have_cost_) state.cost = cost_;
  if (const GraphStream* g = view_.stream()) {
    state.final_blocks.assign(static_cast<std::size_t>(o_.robots), 0);
    for (int b : view_.owner()) {
      const std::uint32_t robot = g->robots()[static_cast<std::size_t>(b)];
      if (robot < state.final_blocks.size()) ++state.final_blocks[robot];
    }
    state.final_cut = cut_measurements(g->graph(), view_.owner());
  }
  cli::write_output(o_.json, online_summary_json(o_, state, fig_));
}

}  // namespace

bool wants_online(const std::vector<std::string>& argv) {
  return std::find(argv.begin(), argv.end(), "--online") != argv.end();
}

int online_agent_main(const std::vector<std::string>& argv) {
  std::unique_ptr<OnlineAgent> agent;
  int code = 0;
  try {
    if (std::find(argv.begin(), argv.end(), "--help") != argv.end()) {
      std::fputs(online_agent_usage(), stdout);
      return 0;
    }
    const OnlineAgentOptions o = parse_online_agent_options(argv);
    agent = std::make_unique<OnlineAgent>(o);
    code = agent->run();
  } catch (const InputError& e) {
    std::cerr << "tessera-agent: error: " << e.what() << "\n";
    code = 2;
  } catch (const std::exception& e) {
    std::cerr << "tessera-agent: run failed: " << e.what() << std::endl;
    code = 1;
  }
  // The result or the error is out; deleting the participants comes last and is bounded, since
  // Fast DDS 2.9 can hang or abort there while a peer's removal races with it
  // (transport/fastdds/teardown_guard.hpp): a hang must not keep a failed or finished agent alive.
  if (agent) {
    const transport::TeardownGuard guard(code, "tessera-agent", std::chrono::seconds(5));
    agent.reset();
  }
  return code;
}

}  // namespace tessera::agent
