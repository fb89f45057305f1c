#include "agent/rejoin.hpp"

#include <chrono>
#include <functional>
#include <random>
#include <string>

#include "agent/lost_for_good.hpp"
#include "transport/run_failure.hpp"

namespace tessera::agent {

using transport::RunFailure;
using transport::Seconds;
using transport::WaitStatus;

namespace {

// `also`: checked on every pass (throws to end the wait early).
void wait_matched(
    transport::AgentSession& s, double timeout_s, const std::string& why,
    const std::function<void()>& also = [] {}) {
  std::string missing;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::nanoseconds>(Seconds(timeout_s));
  while (!s.endpoints_matched(&missing)) {
    also();
    if (s.mailroom().stopped())
      throw RunFailure(s.mailroom().stop_info()->exit_code, s.mailroom().stop_info()->reason,
                       !s.mailroom().stop_info()->remote);
    if (std::chrono::steady_clock::now() > deadline)
      throw RunFailure(transport::kExitRunFailed, "timed out after " + std::to_string(timeout_s) +
                                                      " s " + why +
                                                      ": endpoints not matched with " + missing);
    // endpoints_matched() takes the mailroom lock itself, so it cannot be the predicate of a
    // mailroom wait: re-check on every mailroom notification (matching notifies) or 50 ms.
    s.mailroom().wait_for([] { return false; }, Seconds(0.05));
  }
}

}  // namespace

RollbackRequested request_rejoin(transport::AgentSession& s, std::uint32_t agent_id,
                                 const std::vector<ProtocolSnapshot>& snapshots, double timeout_s) {
  if (snapshots.empty())
    throw RunFailure(transport::kExitBadInput, "the checkpoint holds no round to rejoin from");
  // A run that gave this agent's block away never matches it completely (the survivors may
  // even have finished): the assignment naming it lost is looked for meanwhile.
  wait_matched(s, timeout_s, "waiting to rejoin", [&] { refuse_if_lost(s, agent_id); });
  std::random_device rd;
  const std::uint64_t nonce = (static_cast<std::uint64_t>(rd()) << 32) ^ rd() ^ 1u;
  wire::Control c;
  c.kind(wire::CONTROL_REJOIN);
  c.agent(agent_id);
  c.round(static_cast<std::uint32_t>(snapshots.back().round));
  c.round_prev(static_cast<std::uint32_t>(snapshots.front().round));
  c.nonce(nonce);
  c.reason("agent " + std::to_string(agent_id) + " restarted from its checkpoint");
  // After a re-partition the coordinator no longer answers this agent; the assignment
  // naming it lost (kept by the coordinator's writer, so it reaches us once matched) is the
  // answer: refuse_if_lost throws LostForGood.
  refuse_if_lost(s, agent_id);
  s.send_control(c);
  wire::Control answer;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::nanoseconds>(Seconds(timeout_s));
  WaitStatus st = WaitStatus::kTimeout;
  for (;;) {
    st = s.rollbacks().take(
        [&](const wire::Control& m) { return m.nonce() == nonce && m.agent() == agent_id; },
        Seconds(0.2), &answer);
    if (st != WaitStatus::kTimeout || std::chrono::steady_clock::now() > deadline) break;
    refuse_if_lost(s, agent_id);
  }
  transport::expect_ready(
      st, s.mailroom(), timeout_s,
      "the coordinator to accept the rejoin of agent " + std::to_string(agent_id));
  return RollbackRequested(answer.round(), answer.epoch(), answer.agent());
}

const ProtocolSnapshot& prepare_rollback(transport::AgentSession& s, const CheckpointKeeper& keeper,
                                         const RollbackRequested& order, double timeout_s) {
  const ProtocolSnapshot* snap = keeper.find(static_cast<int>(order.round));
  if (!snap)
    throw RunFailure(transport::kExitRunFailed,
                     "cannot roll back to round " + std::to_string(order.round) +
                         " for the rejoin of agent " + std::to_string(order.agent) +
                         ": this agent keeps rounds " + keeper.held_rounds());
  wait_matched(s, timeout_s, "before resuming at round " + std::to_string(order.round));
  s.set_epoch(order.epoch);
  return *snap;
}

}  // namespace tessera::agent
