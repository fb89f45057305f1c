#include "coordinator/loss_handling.hpp"

#include <algorithm>
#include <iostream>
#include <string>

#include "runtime/elapsed.hpp"
#include "runtime/survivor_step.hpp"
#include "transport/run_failure.hpp"

namespace tessera::coordinator {

using namespace tessera::transport;

LossHandling::LossHandling(const CoordinatorOptions& options, CoordinatorSession& session,
                           const GraphStructure& graph, const wire::PartitionAssignment& base,
                           RunMonitor* monitor, Clock::time_point t_run)
    : options_(options),
      session_(session),
      graph_(graph),
      base_(base),
      monitor_(monitor),
      t_run_(t_run),
      arbiter_(options.agents, options.rejoin_timeout_s),
      arbitrate_(options.rejoin_timeout_s > 0 || options.replicas > 0) {
  record_.owner = base.owner();
  for (std::uint32_t k = 0; k < options.agents; ++k) record_.expected.push_back(k);
  if (arbitrate_) session_.set_agent_loss_tolerated(true);
}

void LossHandling::on_round_status(std::uint32_t sender, std::uint32_t round,
                                   Clock::time_point now) {
  if (sender < record_.expected.size()) {
    // After a re-partition senders are protocol ids: positions among the survivors.
    const std::uint32_t agent = record_.expected[sender];
    if (record_.epoch == 0) arbiter_.on_status(agent, round);
    if (monitor_) monitor_->on_status(agent, round, now);
  }
  if (record_.epoch == 0) record_.last_round = round;
}

LossHandling::Outcome LossHandling::watch(Clock::time_point now) {
  const std::vector<std::uint32_t> lost = session_.lost_agents();
  if (arbitrate_ && record_.epoch == 0)
    for (auto k : lost) arbiter_.on_lost(k, now);
  if (record_.epoch > 0) check_second_loss(lost, now);
  if (monitor_) monitor_->set_lost(lost, now);
  for (const auto& c : session_.rejoins().take_all()) {
    arbiter_.on_rejoin({c.agent(), c.round(), c.round_prev(), c.nonce()}, now);
    if (monitor_)
      monitor_->event("agent " + std::to_string(c.agent()) +
                          " restarted, asks to rejoin (checkpoint rounds " +
                          std::to_string(c.round_prev()) + ", " + std::to_string(c.round()) + ")",
                      now);
  }
  if (arbitrate_ && record_.epoch == 0) return decide(now);
  return Outcome::kNone;
}

void LossHandling::check_second_loss(const std::vector<std::uint32_t>& lost,
                                     Clock::time_point now) {
  // A survivor lost too (for longer than the rejoin window: a loaded host can drop and
  // rediscover a live peer) is a second loss, which the replicas do not cover.
  std::map<std::uint32_t, Clock::time_point> still;
  for (auto k : lost)
    if (std::find(record_.lost.begin(), record_.lost.end(), k) == record_.lost.end())
      still[k] = second_.count(k) ? second_[k] : now;
  second_ = still;
  for (const auto& [k, since] : still)
    if (std::chrono::duration<double>(now - since).count() > options_.rejoin_timeout_s)
      throw RunFailure(kExitRunFailed, "lost agent " + std::to_string(k) +
                                           " after a re-partition: a second loss is not "
                                           "covered by the replicas");
}

LossHandling::Outcome LossHandling::decide(Clock::time_point now) {
  const LossDecision d = arbiter_.decide(now);
  using Kind = LossDecision::Kind;
  if (d.kind == Kind::kGiveUp && options_.replicas > 0) return repartition(d, now);
  if (d.kind == Kind::kGiveUp)
    throw RunFailure(kExitRunFailed, "lost agent " + std::to_string(d.agent) + " of run '" +
                                         options_.net.session.run_id + "': " + d.reason);
  if (d.kind != Kind::kRollback) return Outcome::kNone;
  for (const auto& r : d.rejoined) {
    wire::Control c;
    c.kind(wire::CONTROL_ROLLBACK);
    c.round(d.round);
    c.epoch(d.epoch);
    c.agent(r.agent);
    c.nonce(r.nonce);
    c.reason("agent " + std::to_string(r.agent) + " rejoined");
    session_.send_control(c);
  }
  ++record_.rollbacks;
  report("agent " + std::to_string(d.agent) + " rejoined: every agent rolls back to round " +
             std::to_string(d.round) + " (epoch " + std::to_string(d.epoch) + ")",
         now);
  return Outcome::kRolledBack;
}

// Lost for good: re-partition. Only the agent whose rejoin window closed leaves: a peer
// dropped at the same moment may be a false alarm of a loaded host (it reappears).
LossHandling::Outcome LossHandling::repartition(const LossDecision& d, Clock::time_point now) {
  const std::vector<std::uint32_t> lost = session_.lost_agents();
  if (std::find(lost.begin(), lost.end(), d.agent) == lost.end()) {
    // Alive again: a false alarm of the lease on a busy host, not a loss.
    arbiter_.forget(d.agent);
    std::cerr << "tessera-coordinator: agent " << d.agent
              << " is back (false alarm): no re-partition\n";
    return Outcome::kNone;
  }
  const SurvivorAssignment sa = reassign_for_survivors(graph_, record_.owner, options_.agents,
                                                       {d.agent}, arbiter_.epoch() + 1);
  wire::PartitionAssignment asg = base_;
  asg.epoch(sa.epoch);
  asg.owner(sa.owner);
  asg.survivors(sa.survivors);
  asg.lost(sa.lost);
  session_.publish(asg);
  record_.epoch = sa.epoch;
  record_.owner = sa.owner;
  record_.expected = sa.survivors;
  record_.lost = sa.lost;
  record_.moved_poses = sa.moved_poses;
  record_.cut_edges = sa.cut_edges;
  record_.at_ms = ms_since(t_run_);
  report("agent(s) lost for good; re-partitioned " + std::to_string(sa.moved_poses) +
             " poses among " + std::to_string(sa.survivors.size()) + " survivors (epoch " +
             std::to_string(sa.epoch) + ", " + d.reason + ")",
         now);
  return Outcome::kRepartitioned;
}

void LossHandling::report(const std::string& what, Clock::time_point now) {
  if (monitor_)
    monitor_->event(what, now);
  else
    std::cerr << "tessera-coordinator: " << what << "\n";
}

}  // namespace tessera::coordinator
