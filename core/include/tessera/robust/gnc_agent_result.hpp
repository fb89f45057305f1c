#pragma once
// What a distributed GNC run decided, as every agent holds it once its GncAgent is done
// (robust/gnc_agent.hpp): filled by GncAgent::result() alone, and the common part of what both
// drivers hand on: the in-process driver's GncDistributedResult (robust/gnc_distributed.hpp)
// and agent 0's report over DDS (RobustRunReport, core/runtime/agent_report.hpp). The run's
// rounds and the final solve's figures are not here: each driver counts those its own way.

#include <cstddef>
#include <vector>

namespace tessera {

struct GncAgentResult {
  int outer_iterations = 0;
  /// Measurements by file position, ascending: those of weight < 0.5 (0 when binary) after
  /// the re-check passes and probes.
  std::vector<std::size_t> rejected;
  /// Measurements GNC had rejected whose residual at the inlier set's solution was within the
  /// bound (r^2 <= c^2), taken back by the re-check passes.
  std::size_t readmitted = 0;
  double threshold_squared = 0;  ///< c^2.
  bool weights_converged = false;
  /// Probes after the passes (RobustOptions::recheck_probes) and those that lowered the TLS
  /// cost and stayed.
  int probes = 0;
  int probes_kept = 0;
  /// Message steps (neighbour exchanges and all-agent sums) of the Newton refinements of the
  /// solves before the final one: GNC's weighted solves and the inlier passes. The final
  /// solve's are counted by the driver.
  int refine_message_steps = 0;
  /// Message steps of GNC's own exchanges: poses, votes, weights, rejected sets, verdicts,
  /// start votes, gathers (one per exchange, two per gather at agent 0). A run's message steps
  /// in all: message_steps() below.
  int exchange_steps = 0;
  /// Solve stages of the solves before the final one that open with a pose exchange and end
  /// with a status round, two message steps beyond two a round (opened_solve_stages of
  /// CertifiedAgent::solves(), summed; a weighted solve that starts at its refinement has
  /// none).
  int solve_stages = 0;
};

/// Every wait for peers of a distributed GNC run but its certificates' (docs/robust.md, "JSON
/// and files": message_steps_total): two a round (`rounds`: of every solve, final included),
/// two a solve stage (its opening pose exchange and closing status round: the result's
/// solve_stages + `final_solve_stages`), the Newton refinements' message steps
/// (refine_message_steps + the final solve's `final_refine_steps`) and GNC's own exchanges
/// (exchange_steps). The rounds and the final solve are not in the result (each driver counts
/// them its own way), so they come in beside it; without a final solve its two counts are 0.
long long message_steps(const GncAgentResult& gnc, long long rounds, long long final_solve_stages,
                        long long final_refine_steps);

}  // namespace tessera
