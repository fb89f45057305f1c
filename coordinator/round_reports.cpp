#include "coordinator/round_reports.hpp"

#include <cmath>

namespace tessera::coordinator {

void RoundReports::on_round_status(const wire::RoundStatus& m, std::uint32_t active_agents,
                                   double ms) {
  Partial& p = partial_[{m.round(), m.phase()}];
  p.reported += 1;
  p.cost += m.cost();
  p.grad_norm_sq += m.grad_norm_sq();
  if (p.reported != active_agents) return;
  const CompletedStep step{m.round(), m.phase(), p.cost, p.grad_norm_sq};
  partial_.erase({m.round(), m.phase()});
  on_completed(step, ms);
}

void RoundReports::on_digest(const wire::AgentProgress& m, double ms) {
  if (m.sender() != 0) return;  // the reporter's digests (the others only feed the monitor)
  const std::pair<std::uint32_t, std::uint32_t> at{m.round(), m.phase()};
  if (m.phase() != 0 && (!newest_ || *newest_ < at)) {
    if (!newest_) results_.first_status_ms = ms;  // sent as soon as agent 0 saw it complete
    newest_ = at;
    lines_.on_step({m.round(), m.phase(), m.cost(), m.grad_norm_sq()}, ms);
  }
  if (!m.final()) return;
  // Exact figures from the agent's own clock: the digests themselves come only a few a second.
  results_.completed_statuses = m.completed_rounds();
  results_.last_status_ms = results_.first_status_ms + m.first_to_last_ms();
  results_.have_final_digest = true;
  lines_.finish();
}

void RoundReports::on_completed(const CompletedStep& step, double ms) {
  lines_.on_step(step, ms);
  if (results_.completed_statuses == 0) results_.first_status_ms = ms;
  results_.last_status_ms = ms;
  if (step.phase == 1) ++results_.completed_statuses;
}

bool RoundReports::on_report(const wire::RoundStatus& m) {
  // The report fields ride on the status's numeric fields (core/runtime/round_loop.hpp says which).
  if (m.phase() == kAgentCertificateReportPhase) {
    results_.certificate =
        CertificateReport{m.restart_vote(), m.cost(), m.grad_norm_sq(), m.block_grad_norm(), {}};
    // The bound's parts ride in `coarse` (core/runtime/round_finish.cpp).
    if (m.coarse().size() == 6) {
      DualBound& b = results_.certificate->bound;
      b.relaxation_cost = m.coarse()[0];
      b.trace_lambda = m.coarse()[1];
      b.gradient_norm = m.coarse()[2];
      b.shift = m.coarse()[3];
      b.lower_bound = m.coarse()[4];
      b.method = static_cast<CertificateMethod>(static_cast<int>(m.coarse()[5]));
    }
    return true;
  }
  if (m.phase() == kAgentCertificateBytesPhase) {
    results_.certificate_bytes =
        CertificateTraffic{m.cost(), m.grad_norm_sq(), m.block_grad_norm()};
    return true;
  }
  if (m.phase() == kAgentPhaseTimesPhase) {
    results_.agent_solve_s = m.cost();
    results_.agent_rounding_s = m.grad_norm_sq();
    results_.rounding_cg_iterations = static_cast<std::uint32_t>(m.block_grad_norm());
    if (m.coarse().size() == 2) {  // the interface solve's poses, the message steps
      results_.rounding_interface_poses = static_cast<std::uint32_t>(m.coarse()[0]);
      results_.rounding_message_steps = static_cast<std::uint32_t>(m.coarse()[1]);
    }
    return true;
  }
  if (m.phase() == kAgentSetupTimesPhase) {
    results_.agent_init_s = m.cost();
    results_.agent_handoff_s = m.grad_norm_sq();
    results_.init_early = m.block_grad_norm() != 0.0;
    return true;
  }
  if (m.phase() == kAgentStageProgressPhase) {
    lines_.on_stage(static_cast<std::uint32_t>(m.block_grad_norm()),
                    static_cast<std::uint64_t>(m.grad_norm_sq()), m.cost());
    return true;
  }
  if (m.phase() == kAgentRobustReportPhase) {
    RobustReport r;
    r.outer_iterations = static_cast<int>(m.cost());
    r.readmitted = static_cast<std::size_t>(m.grad_norm_sq());
    r.threshold_squared = m.block_grad_norm();
    r.weights_converged = m.done_vote();
    r.rejected.assign(m.measurement_ids().begin(), m.measurement_ids().end());
    if (m.coarse().size() >= 2) {  // the probes: run, kept
      r.probes = static_cast<int>(m.coarse()[0]);
      r.probes_kept = static_cast<int>(m.coarse()[1]);
    }
    if (m.coarse().size() >= 3) r.refine_steps = static_cast<int>(m.coarse()[2]);
    results_.robust = std::move(r);
    return true;
  }
  if (m.phase() == kAgentFinalReportPhase) {
    results_.final_cost = m.cost();
    results_.final_grad_norm = std::sqrt(m.grad_norm_sq());
    results_.final_restarts = static_cast<std::uint32_t>(m.block_grad_norm());
    results_.have_final_report = true;
    return true;
  }
  return false;
}

}  // namespace tessera::coordinator
