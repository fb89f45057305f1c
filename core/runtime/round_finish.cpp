#include "runtime/round_finish.hpp"

#include <tessera/certification/rounding_gap.hpp>

#include "runtime/distributed_rounding.hpp"

namespace tessera::agent {

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
  if (local.agent_id == 0 && res.robust) {
    RoundStatusMessage r;
    r.round = res.rounds;
    r.phase = kRobustReportPhase;
    r.sender = 0;
    r.cost = res.robust->outer_iterations;
    r.grad_norm_sq = static_cast<double>(res.robust->readmitted);
    r.block_grad_norm = res.robust->threshold_squared;
    r.done_vote = res.robust->weights_converged;
    r.measurement_ids = res.robust->rejected;
    r.coarse = {static_cast<double>(res.robust->probes),
                static_cast<double>(res.robust->probes_kept)};
    channel.send(OutgoingMessage{r, true, {}});
  }
  if (local.agent_id == 0) {  // agent 0's times, for the coordinator's phase split
    RoundStatusMessage t;
    t.round = res.rounds;
    t.phase = kPhaseTimesPhase;
    t.sender = 0;
    t.cost = res.solve_s;
    t.grad_norm_sq = res.rounding_s;
    t.block_grad_norm = res.translation_iterations;
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
