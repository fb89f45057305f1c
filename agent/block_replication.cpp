#include "agent/block_replication.hpp"

#include <chrono>
#include <iostream>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/replica_plan.hpp>
#include <tessera/problem/lifting.hpp>

#include "agent/survivor_exchange.hpp"

namespace tessera::agent {

namespace {

std::string join_ids(const std::vector<std::uint32_t>& ids) {
  std::string out;
  for (auto k : ids) out += (out.empty() ? "" : ", ") + std::to_string(k);
  return out;
}

}  // namespace

void BlockReplication::start(const AgentLocalData& local, DdsProtocolChannel& channel,
                             double timeout_s) {
  std::vector<std::uint32_t> owner = local.owner;
  holders_ = replica_holders(local.structure, owner, local.num_agents, replicas_)[local.agent_id];
  const DistributedOptions defaults;
  Y_ = lift_poses(local.initial,
                  static_cast<int>(local.options.rank ? local.options.rank : defaults.rank));
  send_problem_replicas(session_, local, self_, Y_, holders_);
  // The hand-off topic is volatile: a sample a holder has not received yet (a datagram lost
  // under load waits for the next heartbeat's repair) is gone if this process dies, and with
  // it the measurements only this agent had. So no round before the holders acknowledged it.
  const auto t0 = std::chrono::steady_clock::now();
  const bool held = session_.handoffs_acknowledged(transport::Seconds(timeout_s));
  const long ms = static_cast<long>(
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  if (held)
    log_("replica held by agent(s) " + join_ids(holders_) + " (acknowledged after " +
         std::to_string(ms) + " ms)");
  else
    std::cerr << log_.tag << ": warning: replica not acknowledged by agent(s) "
              << join_ids(holders_) << " within " << timeout_s
              << " s: a loss of this agent may not be covered\n";
  channel.set_intercept([this](const ProtocolMessage& m) {
    const auto* b = std::get_if<PoseBlockMessage>(&m);
    if (!b || b->phase != kReplicaPhase) return false;
    store_.absorb_poses(*b);
    return true;
  });
  log_("replicating to agent(s) " + join_ids(holders_) + " every " +
       std::to_string(replica_every_) + " rounds");
}

void BlockReplication::on_round(const AgentLocalData& local, const ProtocolSnapshot& snap) {
  Y_ = snap.Y;
  round_ = static_cast<std::uint32_t>(snap.round);
  // Replicas only in the first epoch: a second loss is not covered (see the docs).
  if (!taken_ && !holders_.empty() &&
      static_cast<std::uint32_t>(snap.round) % replica_every_ == 0) {
    PoseBlockMessage m = replica_block(local.agent_id, round_, local.d, local.owned, snap.Y);
    session_.send(OutgoingMessage{m, false, holders_});
  }
}

const AgentLocalData& BlockReplication::take_over(const AgentLocalData& local,
                                                  const wire::PartitionAssignment& asg,
                                                  double timeout_s) {
  absorb_problem_replicas(session_, store_);
  const Reassignment r = reassignment_of(asg, local.owner);
  std::cerr << log_.tag << ": agent(s) " << join_ids(r.lost)
            << " lost for good: taking over the re-partition (epoch " << r.epoch << ", "
            << r.survivors.size() << " survivors)\n";
  TakeoverSource src;
  src.self = self_;
  src.local = &local;
  src.Y = Y_;
  src.round = round_;
  src.replicas = &store_;
  taken_ = exchange_takeover(session_, src, r, timeout_s);
  session_.set_epoch(r.epoch, taken_->agent_id);
  log_("take-over complete: " + std::to_string(taken_->owned.size()) + " poses, " +
       std::to_string(taken_->measurements.size()) + " measurements, protocol id " +
       std::to_string(taken_->agent_id) + " of " + std::to_string(taken_->num_agents));
  return *taken_;
}

}  // namespace tessera::agent
