#include "runtime/round_loop.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <tessera/distributed/agent_factory.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <tessera/problem/lifting.hpp>

#include "runtime/distributed_rounding.hpp"
#include "runtime/round_mailbox.hpp"

namespace tessera::agent {

namespace {

DistributedOptions options_of(const RunOptions& o) {
  DistributedOptions opt;
  if (!o.algorithm.empty()) opt.algorithm = parse_algorithm(o.algorithm);
  if (o.rank > 0) opt.rank = static_cast<int>(o.rank);
  if (o.max_rounds > 0) opt.max_rounds = static_cast<int>(o.max_rounds);
  if (o.grad_norm_tolerance > 0) opt.grad_norm_tol = o.grad_norm_tolerance;
  opt.rel_cost_decrease_tol = o.relative_cost_tolerance;
  opt.seed = o.seed;
  opt.certify = o.certify;
  opt.coarse.enabled = o.coarse_every > 0;
  if (o.coarse_every > 0) opt.coarse.every = static_cast<int>(o.coarse_every);
  opt.validate();
  return opt;
}

}  // namespace

void ProtocolChannel::send_all(const std::vector<OutgoingMessage>& messages) {
  for (const auto& m : messages) send(m);
}

std::optional<ProtocolMessage> ProtocolChannel::receive_after(double timeout_s,
                                                              std::size_t /*wake_after*/) {
  return receive(timeout_s);
}

std::optional<ProtocolMessage> ProtocolChannel::receive_awaiting(double timeout_s,
                                                                 const AwaitedMessages& awaited) {
  return receive_after(timeout_s, awaited.senders.size());
}

RoundLoopResult run_round_loop(const AgentLocalData& local, ProtocolChannel& channel,
                               double receive_timeout_s, const RoundLoopHooks& hooks) {
  const DistributedOptions options = options_of(local.options);
  const bool lifted = local.lifted_start.size() > 0;
  if (lifted &&
      (local.lifted_start.cols() != (local.d + 1) * static_cast<Eigen::Index>(local.owned.size()) ||
       local.lifted_start.rows() != options.rank))
    throw std::runtime_error("agent " + std::to_string(local.agent_id) +
                             ": lifted starting point of the wrong shape");
  if (!lifted && local.initial.size() != local.owned.size())
    throw std::runtime_error("agent " + std::to_string(local.agent_id) + ": " +
                             std::to_string(local.initial.size()) + " initial poses for " +
                             std::to_string(local.owned.size()) +
                             " owned poses (run the initialisation stage first)");
  if (options.rank < local.d)
    throw std::runtime_error("rank " + std::to_string(options.rank) +
                             " is below d = " + std::to_string(local.d));

  // Every agent builds the same layout from the structure (endpoints only, 8 bytes a
  // measurement of the whole graph: no Measurement copies, which held 72).
  const BlockLayout layout = make_block_layout(
      local.num_poses, local.structure, std::vector<int>(local.owner.begin(), local.owner.end()));
  const auto& own = layout.poses[local.agent_id];
  if (own.size() != local.owned.size() || !std::equal(own.begin(), own.end(), local.owned.begin()))
    throw std::runtime_error("agent " + std::to_string(local.agent_id) +
                             ": owned poses do not match the assignment");

  // Core's agent, configured as the in-process engine configures it.
  AgentState state(static_cast<int>(local.agent_id), local.d, layout, local.measurements,
                   lifted ? local.lifted_start : lift_poses(local.initial, options.rank));
  const double variables =
      static_cast<double>(options.rank) * (local.d + 1) * static_cast<double>(local.num_poses);
  const auto scheme = make_momentum_scheme(options, layout, variables);
  const RoundConfig config = make_round_config(options, scheme.get());
  Mailbox mail(channel, receive_timeout_s, local.agent_id);
  mail.set_num_agents(local.num_agents);
  RoundLoopResult res;
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<CertifiedAgent> sequence;
  if (!options.certify) {
    RoundProtocol protocol(state, layout, config);
    if (hooks.on_round) protocol.set_round_observer(hooks.on_round);
    mail.run_protocol(
        protocol, hooks.resume_from ? protocol.resume(*hooks.resume_from) : protocol.start(),
        [&] { return "round " + std::to_string(protocol.rounds()) + " of the solve"; });
    res.rounds = static_cast<std::uint32_t>(protocol.rounds());
    res.restarts = static_cast<std::uint32_t>(protocol.restarts());
    res.stop_reason = protocol.stop_reason();
    if (!protocol.trace().empty()) {
      res.relaxation_cost = protocol.trace().back().cost;
      res.grad_norm = protocol.trace().back().grad_norm;
    }
  } else {
    // The certified sequence. Checkpoints and rollbacks cover its first solve stage.
    sequence = std::make_unique<CertifiedAgent>(state, layout, options);
    if (hooks.on_round) sequence->set_round_observer(hooks.on_round);
    mail.run_protocol(
        *sequence, hooks.resume_from ? sequence->resume(*hooks.resume_from) : sequence->start(),
        [&] { return "stage " + std::to_string(sequence->stage()) + " of the certified solve"; });
    const SolveStageRecord& last = sequence->solves().back();
    res.rounds = static_cast<std::uint32_t>(sequence->total_rounds());
    res.restarts = static_cast<std::uint32_t>(sequence->total_restarts());
    res.stop_reason = last.stop_reason;
    if (!last.trace.empty()) {
      res.relaxation_cost = last.trace.back().cost;
      res.grad_norm = last.trace.back().grad_norm;
    }
    res.certified = sequence->certified();
    if (!sequence->certificates().empty())
      res.min_eigenvalue = sequence->certificates().back().result.min_eigenvalue;
    res.certificate_rounds = static_cast<std::uint32_t>(sequence->certificate_iterations());
    res.escape_rounds = static_cast<std::uint32_t>(sequence->escape_trials());
  }
  res.final_rank = static_cast<std::uint32_t>(state.rank());
  const auto t1 = std::chrono::steady_clock::now();

  DistributedRounding rounding(local, layout, state, mail);
  res = rounding.run(std::move(res));
  if (sequence) {
    double escape_bytes = 0.0;
    res.certificate_bytes = static_cast<std::uint64_t>(
        rounding.sum_over_agents(kTraffic, static_cast<double>(mail.certificate_bytes),
                                 static_cast<double>(mail.escape_bytes), &escape_bytes));
    res.escape_bytes = static_cast<std::uint64_t>(escape_bytes);
  }
  res.solve_s = std::chrono::duration<double>(t1 - t0).count();
  res.rounding_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  res.wait_s = mail.wait_s;
  res.send_s = mail.send_s;
  res.rounding_steps = mail.gathers;

  if (local.agent_id == 0 && res.certified) {  // before the final report, which ends the wait
    RoundStatusMessage c;
    c.round = res.rounds;
    c.phase = kCertificateReportPhase;
    c.sender = 0;
    c.cost = res.min_eigenvalue;
    c.grad_norm_sq = res.certificate_rounds;
    c.block_grad_norm = res.final_rank;
    c.restart_vote = *res.certified;
    c.done_vote = true;
    channel.send(OutgoingMessage{c, true, {}});
    RoundStatusMessage b;
    b.round = res.rounds;
    b.phase = kCertificateBytesPhase;
    b.sender = 0;
    b.cost = static_cast<double>(res.certificate_bytes);
    b.grad_norm_sq = static_cast<double>(res.escape_bytes);
    b.block_grad_norm = res.escape_rounds;
    channel.send(OutgoingMessage{b, true, {}});
  }
  if (local.agent_id == 0) {  // agent 0's times, for the coordinator's phase split
    RoundStatusMessage t;
    t.round = res.rounds;
    t.phase = kPhaseTimesPhase;
    t.sender = 0;
    t.cost = res.solve_s;
    t.grad_norm_sq = res.rounding_s;
    channel.send(OutgoingMessage{t, true, {}});
  }
  if (local.agent_id == 0) {  // one report for the coordinator's summary
    RoundStatusMessage st;
    st.round = res.rounds;
    st.phase = kFinalReportPhase;
    st.sender = 0;
    st.cost = res.cost;
    st.grad_norm_sq = res.grad_norm * res.grad_norm;
    st.block_grad_norm = static_cast<double>(res.restarts);
    channel.send(OutgoingMessage{st, true, {}});
  }
  return res;
}

}  // namespace tessera::agent
