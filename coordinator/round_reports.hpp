#pragma once
// What the coordinator reads from the agents' round statuses: the progress of the rounds
// (sums of the agents' cost and squared gradient norm once every active agent reported a
// round, and when rounds completed) and agent 0's reports after the solve (final cost and
// gradient, certificate, certificate traffic). No new traffic: these are the statuses the
// agents exchange anyway, or a few extra ones from agent 0 on the same topic.

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <ostream>
#include <utility>

#include "tessera.h"
#include "transport/topic_names.hpp"

namespace tessera::coordinator {

// Status phases of agent 0's reports (agent/round_loop.hpp: kFinalReportPhase,
// kCertificateReportPhase, kCertificateBytesPhase; the coordinator does not link the agent).
constexpr std::uint32_t kAgentFinalReportPhase = 200;
constexpr std::uint32_t kAgentCertificateReportPhase = 201;
constexpr std::uint32_t kAgentCertificateBytesPhase = 202;

/// Core's round statuses (phase 1: a round; phase 5: a restart of the momentum).
inline bool is_round_status(const wire::RoundStatus& m) {
  return transport::is_solve_status_phase(m.phase());
}

struct CertificateReport {
  bool certified;
  double min_eigenvalue, rounds, final_rank;
};
struct CertificateTraffic {
  double certificate, escape, escape_rounds;  ///< Bytes, bytes, rounds.
};

/// Everything reported so far (for the summary).
struct ReportedResults {
  // From agent 0's final report.
  double final_cost = 0, final_grad_norm = 0;
  std::uint32_t final_restarts = 0;
  bool have_final_report = false;
  std::optional<CertificateReport> certificate;
  std::optional<CertificateTraffic> certificate_bytes;
  // Round timing from the status completions the coordinator sees: excludes the fixed
  // costs (hand-off, initialisation, rounding, shutdown) that the solve time holds.
  double first_status_ms = 0, last_status_ms = 0;
  std::uint32_t completed_statuses = 0;  ///< Rounds (phase 1) every active agent reported.
};

class RoundReports {
 public:
  /// `progress`: print "round K: cost C, grad norm G" to `out` for every completed round.
  RoundReports(bool progress, std::ostream& out) : progress_(progress), out_(out) {}

  /// A round status (is_round_status) of one of `active_agents` agents, `ms` after the
  /// rounds started. Completes the round when every active agent has reported it.
  void on_round_status(const wire::RoundStatus& m, std::uint32_t active_agents, double ms);
  /// One of agent 0's reports (phases kAgent*Phase); false for any other phase.
  bool on_report(const wire::RoundStatus& m);

  /// Forgets the partial sums of rounds not completed (abandoned by a rollback).
  void drop_partial_rounds() { partial_.clear(); }
  /// After a re-partition the survivors' run reports again: drops the partial rounds and
  /// waits for a new final report.
  void restart_after_repartition() {
    partial_.clear();
    results_.have_final_report = false;
  }

  const ReportedResults& results() const { return results_; }

  /// The fewest statuses that can complete a round of `active_agents`: what the partial round
  /// closest to complete still lacks, or `active_agents` when none is partial. A lower bound for
  /// the coordinator's wake-up threshold: a round whose first statuses were taken by the
  /// previous wake-up completes with the rest, not only with the next round's worth (which
  /// the last round never gets: its completion, and the timeline's last_status, then waited
  /// for the final estimates).
  std::size_t statuses_to_complete(std::uint32_t active_agents) const;

 private:
  struct Partial {
    std::uint32_t reported = 0;
    double cost = 0, grad_norm_sq = 0;
  };
  bool progress_;
  std::ostream& out_;
  std::map<std::pair<std::uint32_t, std::uint32_t>, Partial> partial_;  // (round, phase)
  ReportedResults results_;
};

}  // namespace tessera::coordinator
