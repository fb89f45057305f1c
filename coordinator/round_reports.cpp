#include "coordinator/round_reports.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tessera::coordinator {

void RoundReports::on_round_status(const wire::RoundStatus& m, std::uint32_t active_agents,
                                   double ms) {
  Partial& p = partial_[{m.round(), m.phase()}];
  p.reported += 1;
  p.cost += m.cost();
  p.grad_norm_sq += m.grad_norm_sq();
  if (p.reported != active_agents) return;
  if (progress_) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "round %u%s: cost %.10g, grad norm %.3e\n", m.round(),
                  m.phase() == 5 ? " (restart)" : "", p.cost, std::sqrt(p.grad_norm_sq));
    out_ << buf << std::flush;
  }
  partial_.erase({m.round(), m.phase()});
  if (results_.completed_statuses == 0) results_.first_status_ms = ms;
  results_.last_status_ms = ms;
  if (m.phase() == 1) ++results_.completed_statuses;
}

std::size_t RoundReports::statuses_to_complete(std::uint32_t active_agents) const {
  std::size_t fewest = active_agents;
  for (const auto& [key, p] : partial_)
    if (p.reported < active_agents)
      fewest = std::min<std::size_t>(fewest, active_agents - p.reported);
  return std::max<std::size_t>(fewest, 1);
}

bool RoundReports::on_report(const wire::RoundStatus& m) {
  // The report fields ride on the status's numeric fields (agent/round_loop.hpp says which).
  if (m.phase() == kAgentCertificateReportPhase) {
    results_.certificate =
        CertificateReport{m.restart_vote(), m.cost(), m.grad_norm_sq(), m.block_grad_norm()};
    return true;
  }
  if (m.phase() == kAgentCertificateBytesPhase) {
    results_.certificate_bytes =
        CertificateTraffic{m.cost(), m.grad_norm_sq(), m.block_grad_norm()};
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
