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

/// What a partition is chosen for.
///   cut     fewest cut edges (the presets' search alone).
///   rounds  then a final pass for IRBCD's convergence: IRBCD updates one colour class of the
///           block adjacency (quotient) graph per round, so the pass lowers the number of
///           colours while the cut stays within (1 + colour_cut_slack) x the search's cut, and
///           numbers the blocks in colour order (docs/partitioning.md "Partitions for
///           convergence").
enum class PartitionObjective { kCut, kRounds };

/// "cut", "rounds".
const char* objective_name(PartitionObjective objective);
/// Inverse of objective_name; throws InputError listing the valid names.
PartitionObjective parse_objective(const std::string& name);

/// "sequential", "fast", "eco", "strong", "highest".
const char* preset_name(PartitionPreset preset);
/// Inverse of preset_name; throws InputError listing the valid names.
PartitionPreset parse_preset(const std::string& name);

/// Graphs with fewer poses than this get `fast` from auto_preset, larger ones `eco`.
constexpr std::size_t kAutoPresetFastBelow = 2000;
/// The effort `solve` and `launch` choose by default ("auto"): `fast` below kAutoPresetFastBelow
/// vertices, `eco` from there. On small graphs the whole distributed run takes well under a
/// second, eco's search would be 15-25 % of it, and fast with the rounds objective needs the
/// same rounds (1000-pose grid, MIT, CSAIL, intel). On larger ones eco is a few % of the run and
/// fast's partitions cost the long chains rounds (ais2klinik 1238 vs 485, kitti_00 725 vs 519).
PartitionPreset auto_preset(std::size_t num_vertices);
/// parse_preset, plus "auto" = auto_preset(num_vertices).
PartitionPreset parse_preset_for(const std::string& name, std::size_t num_vertices);

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
  PartitionObjective objective = PartitionObjective::kCut;
  /// objective rounds: the largest relative cut increase the colour pass may pay, 0..10.
  double colour_cut_slack = 0.25;
  /// Wall-time cap of the search in seconds, 0 = none (the default: effort is then counted in
  /// operations and a seed fixes the partition). Once passed, no further search step, run or
  /// V-cycle starts and the phases after the search are skipped; one multilevel run always
  /// completes. With a cap the partition depends on the machine's speed and load.
  double time_limit_s = 0.0;
  /// strong / highest: end the search after this many steps in a row without a better cut;
  /// 0 = the preset's own window, max(40, a third of its step budget).
  int stall_steps = 0;

  /// Throws InputError naming the bad field (parts outside 1..64, eps negative, above 1 or not
  /// finite, islands outside 0..8, colour_cut_slack outside 0..10, time_limit_s negative or not
  /// finite, stall_steps negative).
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
  /// The block adjacency graph: pairs of blocks joined by a measurement, and its chromatic
  /// number (the colour classes IRBCD cycles through).
  int adjacent_block_pairs = 0;
  int colours = 0;
};

/// The block adjacency graph of `assignment` (block 0..parts-1 per vertex): the pairs of blocks
/// joined by an edge, and its chromatic number (PartitionResult's two fields).
struct BlockAdjacency {
  int adjacent_block_pairs = 0;
  int colours = 0;
};
BlockAdjacency block_adjacency(const GraphStructure& graph, const std::vector<int>& assignment,
                               int parts);

/// Partitions `graph`. Throws InputError when the options are invalid or N exceeds the number of
/// vertices. The result always satisfies the balance bound and assigns every vertex one block.
PartitionResult partition_graph(const GraphStructure& graph, const PartitionOptions& options);

}  // namespace tessera
