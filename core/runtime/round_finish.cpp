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
    channel.report(CertificateReport{*res.certified, res.min_eigenvalue, res.certificate_rounds,
                                     res.final_rank, res.certificate_bound});
    channel.report(
        CertificateTrafficReport{res.certificate_bytes, res.escape_bytes, res.escape_rounds});
  }
  if (local.agent_id == 0 && res.robust) channel.report(*res.robust);
  if (local.agent_id == 0) {
    // Agent 0's times, for the coordinator's phase split, then one report for its summary.
    channel.report(PhaseTimesReport{res.solve_s, res.rounding_s, res.translation_iterations,
                                    res.rounding_interface_poses, res.rounding_steps});
    channel.report(FinalReport{res.cost, res.grad_norm, res.restarts});
  }
  return res;
}

}  // namespace tessera::agent
