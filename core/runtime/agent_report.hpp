#pragma once
// What agent 0 reports to the coordinator, for its progress lines and the run's summary:
// transport-free, one struct per report, AgentReport any one of them. An agent sends them
// through ProtocolChannel::report (round_loop.hpp); the DDS runtime maps each to one sample of
// wire::AgentReport on its own topic (idl/tessera.idl, transport/report_mapping.hpp), field for
// field. A run sends them in this order: set-up times (after the hand-off), stage progress (during
// the certificate, the refinement and the rounding), then after the rounding the certificate and
// its traffic (when certification ran), the robust report (robust runs), the phase times and the
// final report, which the coordinator's summary waits for.

#include <cstdint>
#include <tessera/certification/dual_bound.hpp>
#include <tessera/robust/gnc_agent_result.hpp>
#include <variant>
#include <vector>

namespace tessera::agent {

/// The stages after the rounds whose progress agent 0 reports (runtime/stage_progress.hpp).
enum class ProgressStage : std::uint32_t { kCertificate = 1, kRounding = 2, kRefinement = 3 };

/// Agent 0's set-up, its clock (seconds).
struct SetupTimesReport {
  double initialization_s = 0.0;  ///< The initialisation stage.
  double handoff_s = 0.0;         ///< The hand-off: exchange and assembly of the local problem.
  /// Its chordal start had been solved while the run started (runtime/early_chordal.hpp).
  bool initialization_early = false;
};

/// Progress of a stage after the rounds: at its start, then at most once per period.
struct StageProgressReport {
  ProgressStage stage = ProgressStage::kCertificate;
  /// The stage's iteration; refinement: refinement_iteration() (stage_progress.hpp).
  std::uint64_t iteration = 0;
  /// Certificate: the current estimate of lambda_min; rounding: the cost its last steps removed
  /// (which its stop compares); refinement: ||grad f|| at its current point.
  double value = 0.0;
};

/// The certificate of the final point (identical on every agent).
struct CertificateReport {
  bool certified = false;
  double min_eigenvalue = 0.0;   ///< The estimate of lambda_min(S).
  std::uint32_t rounds = 0;      ///< Certificate rounds (one per rank tried).
  std::uint32_t final_rank = 0;  ///< r after the staircase.
  DualBound bound;               ///< The last certificate's, and the method that decided it.
};

/// The certification's traffic, summed over the agents.
struct CertificateTrafficReport {
  std::uint64_t certificate_bytes = 0, escape_bytes = 0;
  std::uint32_t escape_rounds = 0;
};

/// What a robust run decided (GncAgentResult, robust/gnc_agent_result.hpp: the same on every
/// agent) and agent 0's final solve's refinement.
struct RobustRunReport : GncAgentResult {
  /// Message steps of the final solve's Newton refinement (0 without a final solve).
  int final_refine_steps = 0;
  /// Solve stages of the final solve (0 without one).
  int final_solve_stages = 0;
};

/// Agent 0's time after the rounds began, its clock (seconds), and how the rounding went: the
/// coordinator splits the time after the last round into certificate and rounding with these.
struct PhaseTimesReport {
  double solve_s = 0.0;                      ///< Core's protocol: rounds, certificate and escapes.
  double rounding_s = 0.0;                   ///< The distributed rounding.
  std::uint32_t rounding_cg_iterations = 0;  ///< Its translation CG iterations.
  std::uint32_t rounding_interface_poses = 0;  ///< Its exact interface solve's (0: the CG ran).
  std::uint32_t rounding_message_steps = 0;    ///< Each one a wait for peers.
};

/// The rounded estimate's figures (whole graph): the last report of a run.
struct FinalReport {
  double cost = 0.0;       ///< Of the rounded poses.
  double grad_norm = 0.0;  ///< ||grad f|| at the final lifted iterate.
  std::uint32_t restarts = 0;
};

using AgentReport =
    std::variant<SetupTimesReport, StageProgressReport, CertificateReport, CertificateTrafficReport,
                 RobustRunReport, PhaseTimesReport, FinalReport>;

}  // namespace tessera::agent
