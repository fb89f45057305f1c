#include "runtime/round_finish.hpp"

#include <tessera/certification/rounding_gap.hpp>

#include "runtime/distributed_rounding.hpp"

namespace tessera::agent {
namespace {

// Agent 0's report of `phase` to the coordinator, its three values in the status's fields.
RoundStatusMessage agent0_report(std::uint32_t round, std::uint32_t phase, double cost,
                                 double grad_norm_sq, double block_grad_norm) {
  RoundStatusMessage m;
  m.round = round;
  m.phase = phase;
  m.sender = 0;
  m.cost = cost;
  m.grad_norm_sq = grad_norm_sq;
  m.block_grad_norm = block_grad_norm;
  return m;
}

}  // namespace

RoundLoopResult round_and_report(const AgentLocalData& local, const BlockLayout& layout,
                                 const AgentState& state, Mailbox& mail, ProtocolChannel& channel,
                                 RoundLoopResult res, bool certified_sequence,
                                 std::chrono::steady_clock::time_point solve_start) {
  const auto t1 = std::chrono::steady_clock::now();

  DistributedRounding rounding(local, layout, state, mail);
  res = rounding.run(std::move(res));
  res.certified = estimate_certified(res.certified, res.cost, res.relaxation_cost);
  if (certified_sequence) {
    double escape_bytes = 0.0;
    res.certificate_bytes = static_cast<std::uint64_t>(
        rounding.sum_over_agents(kTraffic, static_cast<double>(mail.certificate_bytes),
                                 static_cast<double>(mail.escape_bytes), &escape_bytes));
    res.escape_bytes = static_cast<std::uint64_t>(escape_bytes);
  }
  res.solve_s = std::chrono::duration<double>(t1 - solve_start).count();
  res.rounding_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  res.wait_s = mail.wait_s;
  res.send_s = mail.send_s;
  res.rounding_steps = mail.gathers;

  auto send = [&channel](const RoundStatusMessage& m) {
    channel.send(OutgoingMessage{m, true, {}});
  };
  if (local.agent_id == 0 && res.certified) {  // before the final report, which ends the wait
    RoundStatusMessage c = agent0_report(res.rounds, kCertificateReportPhase, res.min_eigenvalue,
                                         res.certificate_rounds, res.final_rank);
    c.restart_vote = *res.certified;
    c.done_vote = true;
    const DualBound& b = res.certificate_bound;
    c.coarse = {b.relaxation_cost, b.trace_lambda, b.gradient_norm,
                b.shift,           b.lower_bound,  static_cast<double>(b.method)};
    send(c);
    send(agent0_report(res.rounds, kCertificateBytesPhase,
                       static_cast<double>(res.certificate_bytes),
                       static_cast<double>(res.escape_bytes), res.escape_rounds));
  }
  if (local.agent_id == 0 && res.robust) {
    RoundStatusMessage r =
        agent0_report(res.rounds, kRobustReportPhase, res.robust->outer_iterations,
                      static_cast<double>(res.robust->readmitted), res.robust->threshold_squared);
    r.done_vote = res.robust->weights_converged;
    r.measurement_ids = res.robust->rejected;
    r.coarse = {static_cast<double>(res.robust->probes),
                static_cast<double>(res.robust->probes_kept),
                static_cast<double>(res.robust->refine_steps)};
    send(r);
  }
  if (local.agent_id == 0) {
    // Agent 0's times, for the coordinator's phase split, then one report for its summary.
    RoundStatusMessage times = agent0_report(res.rounds, kPhaseTimesPhase, res.solve_s,
                                             res.rounding_s, res.translation_iterations);
    times.coarse = {static_cast<double>(res.rounding_interface_poses),
                    static_cast<double>(res.rounding_steps)};
    send(times);
    send(agent0_report(res.rounds, kFinalReportPhase, res.cost, res.grad_norm * res.grad_norm,
                       static_cast<double>(res.restarts)));
  }
  return res;
}

}  // namespace tessera::agent
