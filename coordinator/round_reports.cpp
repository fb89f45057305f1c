#include "coordinator/round_reports.hpp"

#include <type_traits>
#include <variant>

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

void RoundReports::on_report(const agent::AgentReport& report) {
  std::visit(
      [this](const auto& r) {
        using R = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<R, agent::SetupTimesReport>) {
          results_.setup = r;
        } else if constexpr (std::is_same_v<R, agent::StageProgressReport>) {
          lines_.on_stage(static_cast<std::uint32_t>(r.stage), r.iteration, r.value);
        } else if constexpr (std::is_same_v<R, agent::CertificateReport>) {
          results_.certificate = r;
        } else if constexpr (std::is_same_v<R, agent::CertificateTrafficReport>) {
          results_.certificate_bytes = r;
        } else if constexpr (std::is_same_v<R, agent::RobustRunReport>) {
          results_.robust = r;
        } else if constexpr (std::is_same_v<R, agent::PhaseTimesReport>) {
          results_.phase_times = r;
        } else {
          static_assert(std::is_same_v<R, agent::FinalReport>);
          results_.final_report = r;
          results_.have_final_report = true;
        }
      },
      report);
}

}  // namespace tessera::coordinator
