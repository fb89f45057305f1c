#pragma once
// The figures an online agent gathers while it runs, and its JSON summary (`--json`).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <tessera/online/graph_stream.hpp>
#include <vector>

#include "agent/online_agent_options.hpp"
#include "agent/online_solve_outcome.hpp"
#include "json_writer.hpp"

namespace tessera::agent {

/// Counted over the whole run; each entry of `updates`, `certificates` and `faults` is one
/// element of the summary's array of that name.
struct OnlineFigures {
  std::vector<cli::JsonObject> updates;       ///< One per epoch that solved (or skipped) new data.
  std::vector<cli::JsonObject> certificates;  ///< One per certificate of the growing graph.
  std::vector<cli::JsonObject> faults;        ///< One per take-over of lost agents.
  std::vector<double> batch_latency_s;        ///< Arrival to solved, per batch.
  /// The same with the solve's CPU time in place of its wall time (BatchArrivals::absorbed).
  std::vector<double> batch_latency_cpu_s;
  std::uint64_t bytes_sent = 0, messages_sent = 0, report_bytes = 0;
  std::uint64_t idle_waits = 0;
  int rounds = 0, solves = 0;
  double cpu_s = 0.0;
  std::size_t publications = 0;
};

/// The q-quantile of `v` (nearest rank; 0 for an empty `v`).
double percentile(std::vector<double> v, double q);

/// What the summary reports besides the figures.
struct OnlineSummaryState {
  std::uint32_t epochs = 0;
  const GraphStream* graph = nullptr;  ///< The graph received so far (null: none yet).
  SolveOutcome final_solve;
  double wall_s = 0.0;
  std::optional<double> cost;  ///< f of the rounded estimate: only the lead's answer has it.
  /// At the end: the poses of robot r's block (r = 0..robots-1; 0 for a robot with no block)
  /// and the measurements between two blocks.
  std::vector<std::size_t> final_blocks;
  std::size_t final_cut = 0;
};

/// The agent's summary as JSON text (fields as documented in docs/online.md).
std::string online_summary_json(const OnlineAgentOptions& o, const OnlineSummaryState& state,
                                const OnlineFigures& figures);

}  // namespace tessera::agent
