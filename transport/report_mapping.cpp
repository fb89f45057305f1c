#include "transport/report_mapping.hpp"

#include <type_traits>
#include <vector>

namespace tessera::transport {

namespace {

wire::AgentReportBody body_of(const agent::SetupTimesReport& r) {
  wire::SetupTimesReport w;
  w.initialization_s(r.initialization_s);
  w.handoff_s(r.handoff_s);
  w.initialization_early(r.initialization_early);
  wire::AgentReportBody b;
  b.setup_times(std::move(w));
  return b;
}

wire::AgentReportBody body_of(const agent::StageProgressReport& r) {
  wire::StageProgressReport w;
  w.stage(static_cast<std::uint32_t>(r.stage));
  w.iteration(r.iteration);
  w.value(r.value);
  wire::AgentReportBody b;
  b.stage_progress(std::move(w));
  return b;
}

wire::AgentReportBody body_of(const agent::CertificateReport& r) {
  wire::CertificateReport w;
  w.certified(r.certified);
  w.min_eigenvalue(r.min_eigenvalue);
  w.rounds(r.rounds);
  w.final_rank(r.final_rank);
  w.relaxation_cost(r.bound.relaxation_cost);
  w.trace_lambda(r.bound.trace_lambda);
  w.gradient_norm(r.bound.gradient_norm);
  w.shift(r.bound.shift);
  w.lower_bound(r.bound.lower_bound);
  w.method(static_cast<std::uint8_t>(r.bound.method));
  wire::AgentReportBody b;
  b.certificate(std::move(w));
  return b;
}

wire::AgentReportBody body_of(const agent::CertificateTrafficReport& r) {
  wire::CertificateTrafficReport w;
  w.certificate_bytes(r.certificate_bytes);
  w.escape_bytes(r.escape_bytes);
  w.escape_rounds(r.escape_rounds);
  wire::AgentReportBody b;
  b.certificate_traffic(std::move(w));
  return b;
}

wire::AgentReportBody body_of(const agent::RobustRunReport& r) {
  wire::RobustReport w;
  w.outer_iterations(static_cast<std::uint32_t>(r.outer_iterations));
  w.rejected(std::vector<std::uint64_t>(r.rejected.begin(), r.rejected.end()));
  w.readmitted(r.readmitted);
  w.threshold_squared(r.threshold_squared);
  w.weights_converged(r.weights_converged);
  w.probes(static_cast<std::uint32_t>(r.probes));
  w.probes_kept(static_cast<std::uint32_t>(r.probes_kept));
  w.refine_steps(static_cast<std::uint32_t>(r.refine_message_steps));
  w.exchange_steps(static_cast<std::uint32_t>(r.exchange_steps));
  w.final_refine_steps(static_cast<std::uint32_t>(r.final_refine_steps));
  w.solve_stages(static_cast<std::uint32_t>(r.solve_stages));
  w.final_solve_stages(static_cast<std::uint32_t>(r.final_solve_stages));
  wire::AgentReportBody b;
  b.robust(std::move(w));
  return b;
}

wire::AgentReportBody body_of(const agent::PhaseTimesReport& r) {
  wire::PhaseTimesReport w;
  w.solve_s(r.solve_s);
  w.rounding_s(r.rounding_s);
  w.rounding_cg_iterations(r.rounding_cg_iterations);
  w.rounding_interface_poses(r.rounding_interface_poses);
  w.rounding_message_steps(r.rounding_message_steps);
  wire::AgentReportBody b;
  b.phase_times(std::move(w));
  return b;
}

wire::AgentReportBody body_of(const agent::FinalReport& r) {
  wire::FinalReport w;
  w.cost(r.cost);
  w.grad_norm(r.grad_norm);
  w.restarts(r.restarts);
  wire::AgentReportBody b;
  b.final_report(std::move(w));
  return b;
}

agent::ProgressStage stage_of(std::uint32_t v) {
  switch (v) {
    case static_cast<std::uint32_t>(agent::ProgressStage::kCertificate):
    case static_cast<std::uint32_t>(agent::ProgressStage::kRounding):
    case static_cast<std::uint32_t>(agent::ProgressStage::kRefinement):
      return static_cast<agent::ProgressStage>(v);
  }
  throw TransportError("malformed agent report: stage progress of unknown stage " +
                       std::to_string(v));
}

CertificateMethod method_of(std::uint8_t v) {
  switch (v) {
    case static_cast<std::uint8_t>(CertificateMethod::kNone):
    case static_cast<std::uint8_t>(CertificateMethod::kExact):
    case static_cast<std::uint8_t>(CertificateMethod::kLobpcg):
      return static_cast<CertificateMethod>(v);
  }
  throw TransportError("malformed agent report: certificate method " + std::to_string(v) +
                       " is none of 0 (none), 1 (exact), 2 (lobpcg)");
}

}  // namespace

wire::AgentReport to_wire_report(const agent::AgentReport& report, const std::string& run_id,
                                 std::uint32_t sender, std::uint32_t epoch) {
  wire::AgentReport w;
  w.run_id(run_id);
  w.sender(sender);
  w.epoch(epoch);
  w.body(std::visit([](const auto& r) { return body_of(r); }, report));
  return w;
}

agent::AgentReport from_wire(const wire::AgentReport& w) {
  const wire::AgentReportBody& b = w.body();
  switch (b._d()) {
    case wire::REPORT_SETUP_TIMES: {
      const auto& x = b.setup_times();
      return agent::SetupTimesReport{x.initialization_s(), x.handoff_s(), x.initialization_early()};
    }
    case wire::REPORT_STAGE_PROGRESS: {
      const auto& x = b.stage_progress();
      return agent::StageProgressReport{stage_of(x.stage()), x.iteration(), x.value()};
    }
    case wire::REPORT_CERTIFICATE: {
      const auto& x = b.certificate();
      agent::CertificateReport r;
      r.certified = x.certified();
      r.min_eigenvalue = x.min_eigenvalue();
      r.rounds = x.rounds();
      r.final_rank = x.final_rank();
      r.bound.relaxation_cost = x.relaxation_cost();
      r.bound.trace_lambda = x.trace_lambda();
      r.bound.gradient_norm = x.gradient_norm();
      r.bound.shift = x.shift();
      r.bound.lower_bound = x.lower_bound();
      r.bound.method = method_of(x.method());
      return r;
    }
    case wire::REPORT_CERTIFICATE_TRAFFIC: {
      const auto& x = b.certificate_traffic();
      return agent::CertificateTrafficReport{x.certificate_bytes(), x.escape_bytes(),
                                             x.escape_rounds()};
    }
    case wire::REPORT_ROBUST: {
      const auto& x = b.robust();
      agent::RobustRunReport r;
      r.outer_iterations = static_cast<int>(x.outer_iterations());
      r.rejected.assign(x.rejected().begin(), x.rejected().end());
      r.readmitted = static_cast<std::size_t>(x.readmitted());
      r.threshold_squared = x.threshold_squared();
      r.weights_converged = x.weights_converged();
      r.probes = static_cast<int>(x.probes());
      r.probes_kept = static_cast<int>(x.probes_kept());
      r.refine_message_steps = static_cast<int>(x.refine_steps());
      r.exchange_steps = static_cast<int>(x.exchange_steps());
      r.final_refine_steps = static_cast<int>(x.final_refine_steps());
      r.solve_stages = static_cast<int>(x.solve_stages());
      r.final_solve_stages = static_cast<int>(x.final_solve_stages());
      return r;
    }
    case wire::REPORT_PHASE_TIMES: {
      const auto& x = b.phase_times();
      return agent::PhaseTimesReport{x.solve_s(), x.rounding_s(), x.rounding_cg_iterations(),
                                     x.rounding_interface_poses(), x.rounding_message_steps()};
    }
    case wire::REPORT_FINAL: {
      const auto& x = b.final_report();
      return agent::FinalReport{x.cost(), x.grad_norm(), x.restarts()};
    }
  }
  throw TransportError("malformed agent report: unknown kind " +
                       std::to_string(static_cast<int>(b._d())));
}

}  // namespace tessera::transport
