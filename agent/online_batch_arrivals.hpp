#pragma once
// When each batch of an online run reached this agent, kept until the batch entered the graph:
// the summary's batch latency runs from a batch's arrival to the end of the solve that took
// it in (docs/online.md).

#include <cstdint>
#include <map>
#include <tessera/online/graph_stream.hpp>
#include <utility>
#include <vector>

namespace tessera::agent {

class BatchArrivals {
 public:
  /// Batch `sequence` of `robot` arrived at `at_s` (the run's clock); a copy read again keeps
  /// the first arrival.
  void arrived(std::uint32_t robot, std::uint64_t sequence, double at_s);

  /// Appends to `latencies` the latency of every batch `graph` absorbed, for a solve that ended
  /// at `solved_at_s`, and forgets those batches. Returns the arrival of the oldest of them, or
  /// `step_start_s` when that is earlier.
  /// With `cpu_latencies`, also appends each batch's latency with the solve's CPU time
  /// `step_cpu_s` in place of its wall time (its wait until `step_start_s` plus `step_cpu_s`:
  /// what the latency would be with this agent alone on its core).
  double absorbed(const GraphStream& graph, double solved_at_s, double step_start_s,
                  std::vector<double>& latencies, double step_cpu_s = 0.0,
                  std::vector<double>* cpu_latencies = nullptr);

 private:
  std::map<std::pair<std::uint32_t, std::uint64_t>, double> arrived_at_;
};

}  // namespace tessera::agent
