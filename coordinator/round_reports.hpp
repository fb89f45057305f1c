#pragma once
// What the coordinator reads about the rounds: their progress (the sums of the agents' cost
// and squared gradient norm of each completed status step, and when steps completed) and
// agent 0's reports (runtime/agent_report.hpp: set-up times, stage progress, and after the
// solve the certificate and its traffic, the robust decisions, phase times, final cost and
// gradient). The progress comes from agent 0's progress digests (agent/progress_digest.hpp: a
// few a second, and its last one with the exact round timing), or, while the coordinator
// arbitrates lost agents, from every agent's round statuses themselves. No traffic of its own.

#include <cstdint>
#include <map>
#include <optional>
#include <ostream>
#include <utility>
#include <vector>

#include "runtime/agent_report.hpp"
#include "runtime/progress_printer.hpp"
#include "tessera.h"
#include "transport/topic_names.hpp"

namespace tessera::coordinator {

/// Core's round statuses (phase 1: a round; phase 5: a restart of the momentum).
inline bool is_round_status(const wire::RoundStatus& m) {
  return transport::is_solve_status_phase(m.phase());
}

/// Everything reported so far (for the summary).
struct ReportedResults {
  // Agent 0's reports as they came (runtime/agent_report.hpp); none before its report came.
  std::optional<agent::SetupTimesReport> setup;
  std::optional<agent::CertificateReport> certificate;
  std::optional<agent::CertificateTrafficReport> certificate_bytes;
  std::optional<agent::RobustRunReport> robust;
  std::optional<agent::PhaseTimesReport> phase_times;
  /// The last final report; `have_final_report` says whether it is the current run's (false
  /// before it came and again after a re-partition, until the survivors' run sends its own).
  agent::FinalReport final_report;
  bool have_final_report = false;
  // Round timing from the status completions: excludes the fixed costs (hand-off,
  // initialisation, rounding, shutdown) that the solve time holds. From digests: the first is
  // when agent 0's first completion reached the coordinator, the last that plus agent 0's own
  // first-to-last time, and the count agent 0's.
  double first_status_ms = 0, last_status_ms = 0;
  std::uint32_t completed_statuses = 0;  ///< Rounds (phase 1) every active agent reported.
  bool have_final_digest = false;        ///< Agent 0's last progress digest arrived.
};

class RoundReports {
 public:
  /// `progress`: print "round K: cost C, grad norm G" to `out` for completed rounds
  /// (ProgressPrinter: the first, restarts, the last, at most ten a second in between).
  /// `min_interval_ms`: ProgressPrinter's (0: every completed step).
  RoundReports(bool progress, std::ostream& out, double min_interval_ms = 100.0)
      : lines_(progress, out, min_interval_ms) {}

  /// A round status (is_round_status) of one of `active_agents` agents, `ms` after the
  /// rounds started. Completes the round when every active agent has reported it.
  void on_round_status(const wire::RoundStatus& m, std::uint32_t active_agents, double ms);
  /// A progress digest, `ms` after the rounds started; only agent 0's (the reporter's) count.
  void on_digest(const wire::AgentProgress& m, double ms);
  /// The rounds are over: prints the last completed round if its line was held back.
  void finish() { lines_.finish(); }
  /// One of agent 0's reports (runtime/agent_report.hpp).
  void on_report(const agent::AgentReport& report);

  /// Forgets the partial sums of rounds not completed (abandoned by a rollback).
  void drop_partial_rounds() { partial_.clear(); }
  /// After a re-partition the survivors' run reports again: drops the partial rounds and
  /// waits for a new final report.
  void restart_after_repartition() {
    partial_.clear();
    results_.have_final_report = false;
  }

  const ReportedResults& results() const { return results_; }

 private:
  struct Partial {
    std::uint32_t reported = 0;
    double cost = 0, grad_norm_sq = 0;
  };
  void on_completed(const CompletedStep& step, double ms);
  ProgressPrinter lines_;
  std::optional<std::pair<std::uint32_t, std::uint32_t>> newest_;  // from digests: round, phase
  std::map<std::pair<std::uint32_t, std::uint32_t>, Partial> partial_;  // (round, phase)
  ReportedResults results_;
};

}  // namespace tessera::coordinator
