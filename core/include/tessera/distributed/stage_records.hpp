#pragma once
// What each stage of the certified sequence (certified_agent.hpp) leaves behind, identical on
// every agent.

#include <cstdint>
#include <string>
#include <tessera/certification/distributed_certificate.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <vector>

namespace tessera {

struct SolveStageRecord {
  std::uint32_t stage = 0;
  int rank = 0;
  int rounds = 0;
  int restarts = 0;
  std::string stop_reason;
  std::vector<RoundRecord> trace;
  double grad_tol = 0.0;  ///< The stage's gradient-norm tolerance.
  /// A refinement: the same rank continued to StaircaseOptions::grad_norm_tol after an
  /// inconclusive certificate at the solver's tolerance.
  bool refine = false;
  /// The stage opened with a pose exchange and its rounds ended with a status round, two
  /// message steps of its own; false when it started at its Newton refinement
  /// (CertifiedAgent::start_at_refinement: no rounds, an empty trace until the refinement's
  /// point).
  bool opened = true;
};

/// The stages of `solves` that opened with a pose exchange and a status round
/// (SolveStageRecord::opened): a run's message steps count two for each.
inline int opened_solve_stages(const std::vector<SolveStageRecord>& solves) {
  int n = 0;
  for (const auto& s : solves) n += s.opened ? 1 : 0;
  return n;
}

struct CertifyStageRecord {
  std::uint32_t stage = 0;
  int rank = 0;
  DistributedCertificateResult result;  ///< eigenvector left empty
};

struct EscapeStageRecord {
  std::uint32_t stage = 0;
  int rank = 0;  ///< Rank escaped from.
  bool success = false;
  int trials = 0;
  double alpha = 0.0;
  double cost = 0.0;
};

}  // namespace tessera
