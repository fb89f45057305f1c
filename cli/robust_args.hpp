#pragma once
// The robust-solve options of `tessera solve` (--robust, --inlier-threshold, ...) and the
// JSON fields and --rejected file a robust solve adds to its output (docs/robust.md).

#include <cstddef>
#include <string>
#include <tessera/robust/gnc_agent_result.hpp>
#include <tessera/robust/robust_options.hpp>
#include <vector>

#include "arguments.hpp"
#include "json_writer.hpp"

namespace tessera::cli {

/// Valued option names (without "--"), null-terminated.
extern const char* const kRobustValued[];
/// Help text of those options.
extern const char* const kRobustHelp;

/// RobustOptions::final_refine as `--gnc-final-refine` spells it: "newton" or "none".
const char* final_refine_name(const RobustOptions& options);
/// "newton" -> true, "none" -> false; InputError naming the flag otherwise.
bool parse_final_refine(const std::string& name);

/// The options as given (defaults for absent ones), validated: InputError names the option.
RobustOptions parse_robust_options(const Arguments& args);

/// What a robust solve reports besides the usual summary.
struct RobustSummary {
  RobustOptions options;
  int outer_iterations = 0;
  int total_iterations = 0;  ///< Solver iterations (or rounds) of every solve, final included.
  /// Centralized: truncated-CG iterations of every solve (-1: distributed, not written).
  int total_cg_iterations = -1;
  std::size_t measurements = 0;
  std::vector<std::size_t> rejected;  ///< Indices over the EDGE lines, from 0, ascending.
  double threshold_squared = 0;
  bool weights_converged = false;
  std::size_t readmitted = 0;  ///< Rejected by GNC, taken back at the inlier set's solution.
  /// Probes after the re-check passes (distributed: RobustOptions::recheck_probes; centralized:
  /// the cluster probes, GncCentralizedOptions::cluster_probes, and the return probes) and those
  /// that lowered the TLS cost and stayed.
  int probes = 0;
  int probes_kept = 0;
  /// Centralized: swap probes (RobustOptions::swap_probes) and those that stayed (-1: distributed,
  /// not written).
  int swap_probes = -1;
  int swap_probes_kept = 0;
};

/// Appends robust, outer_iterations, total_iterations, inliers, outliers, rejected,
/// inlier_threshold_squared, known_inliers, gnc_mu_step, weights_converged, readmitted,
/// probes, probes_kept, gnc_final_refine (and total_cg_iterations, swap_probes and
/// swap_probes_kept when set).
void add_robust_fields(JsonObject& json, const RobustSummary& summary);

/// A distributed robust run's fields: add_robust_fields of `options` and the agents' result
/// (GncAgentResult: the in-process driver's GncDistributedResult or agent 0's report over DDS),
/// with `rounds` (the rounds of every solve, final included) and the graph's `measurements`;
/// then its message steps, each a wait for peers (docs/robust.md): total_rounds,
/// gnc_refine_steps, gnc_exchange_steps, final_refine_steps (the final solve's Newton
/// refinement's, `final_refine_steps`), solve_stages (GncAgentResult::solve_stages +
/// `final_solve_stages`: each opens with a pose exchange and ends with a status round) and
/// message_steps_total (core's message_steps of GncAgentResult: 2 x rounds + 2 x solve_stages +
/// the other three; `tessera solve` and the coordinator's summary alike).
void add_distributed_robust_fields(JsonObject& json, const RobustOptions& options,
                                   const GncAgentResult& gnc, long long rounds,
                                   std::size_t measurements, long long final_refine_steps,
                                   long long final_solve_stages);

/// Writes one rejected index per line to `path` (InputError when it cannot).
void write_rejected(const std::string& path, const std::vector<std::size_t>& rejected);

}  // namespace tessera::cli
