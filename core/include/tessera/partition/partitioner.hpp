#pragma once
// Splitting a pose graph's structure into N balanced blocks (one per agent) with few cut edges.
// Options in, result out: partition_graph(structure, options) -> PartitionResult.
//
// Presets (details and measured quality in docs/partitioning.md):
//   sequential  N contiguous id ranges whose sizes differ by at most one (the usual baseline).
//   fast        one multilevel run (heavy-edge matching, recursive-bisection initial partition,
//               k-way FM while uncoarsening) plus one V-cycle.
//   eco         a few multilevel runs, the best one improved by V-cycles.
//   strong      a small memetic search: population of multilevel runs improved by combine
//               operations and mutations.
//   highest     the same search with a larger population and many more steps.
// Every preset is deterministic for a given seed; effort is counted in operations, never time.

#include <cstdint>
#include <string>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partition_metrics.hpp>
#include <vector>

namespace tessera {

enum class PartitionPreset { kSequential, kFast, kEco, kStrong, kHighest };

/// "sequential", "fast", "eco", "strong", "highest".
const char* preset_name(PartitionPreset preset);
/// Inverse of preset_name; throws InputError listing the valid names.
PartitionPreset parse_preset(const std::string& name);

struct PartitionOptions {
  int parts = 2;  ///< N, number of blocks: 1..64 (and at most the number of vertices).
  PartitionPreset preset = PartitionPreset::kEco;
  /// Balance slack: every block holds at most floor((1 + eps) * ceil(n / N)) vertices.
  /// Range 0..1; default 0.03 (KaHIP's default and the reference paper's setting).
  double eps = 0.03;
  std::uint64_t seed = 1;  ///< Same seed, same graph, same preset => same partition.
  /// Search islands of strong / highest, each a whole search on its own thread
  /// (docs/partitioning.md item 10): 0 = the preset's own (highest 2, strong 1); else 1..8.
  /// highest adds a short island (a fifth of the step budget) to any count but 1, where that
  /// fifth is at least its population (docs/partitioning.md item 10).
  /// Each island costs a full search's CPU time, so a caller that shares the cores with other
  /// work (e.g. agents starting up) may want 1. The partition depends on this value and the
  /// seed, never on the machine's core count.
  int islands = 0;

  /// Throws InputError naming the bad field (parts outside 1..64, eps negative, above 1 or not
  /// finite, islands outside 0..8).
  void validate() const;
};

/// What one phase of the partitioner did (for logs and --json).
struct PartitionPhase {
  std::string name;    ///< e.g. "multilevel", "v-cycle", "population", "evolution".
  std::string detail;  ///< Human-readable: levels, coarsest size, number of runs...
  long long cut = 0;   ///< Best cut (sum of cut edge weights) after this phase.
  double ms = 0.0;     ///< Wall time of this phase.
};

struct PartitionResult {
  std::vector<int> assignment;  ///< Block id 0..N-1 of every vertex.
  PartitionMetrics metrics;
  std::size_t max_block_size = 0;  ///< The balance bound used, floor((1+eps) ceil(n/N)).
  double time_ms = 0.0;            ///< Wall time of the partitioning (metrics excluded).
  double cpu_ms = 0.0;  ///< Process CPU time of the same (tells contention apart on busy hosts).
  std::vector<PartitionPhase> trace;
};

/// Partitions `graph`. Throws InputError when the options are invalid or N exceeds the number of
/// vertices. The result always satisfies the balance bound and assigns every vertex one block.
PartitionResult partition_graph(const GraphStructure& graph, const PartitionOptions& options);

}  // namespace tessera
