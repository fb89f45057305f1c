#pragma once
// When agents are lost for good, their poses must go to the survivors. The survivors already
// hold their own blocks (poses, measurements, current iterate), so a good new assignment keeps
// every survivor's block where it is and only places the lost poses: few poses move (only the
// lost ones), the balance bound holds over the survivors, and the lost block is split along its
// own structure so the cut grows little. Structure only (which poses are joined, how many
// measurements join them), like every partitioner here.
//
// Strategies:
//   grow   (default) every survivor keeps its poses; the lost poses are grown into the
//          neighbouring survivor blocks, strongest connection first (heaviest edge weight to an
//          already placed neighbour, block with room), then improved by a few passes of
//          positive-gain moves of the lost poses only. Moves exactly the lost poses.
//   fresh  partition the whole structure again for the survivors (core's multilevel
//          partitioner, `preset`), then give each new block to the survivor whose old block it
//          overlaps most (greedy on the overlap matrix). Usually a smaller cut, many more moves.

#include <cstddef>
#include <cstdint>
#include <string>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partition_metrics.hpp>
#include <tessera/partition/partitioner.hpp>
#include <vector>

namespace tessera {

enum class SurvivorStrategy { kGrow, kFresh };

/// "grow", "fresh".
const char* survivor_strategy_name(SurvivorStrategy s);
/// Inverse of survivor_strategy_name; throws InputError listing the valid names.
SurvivorStrategy parse_survivor_strategy(const std::string& name);

struct SurvivorRepartitionOptions {
  SurvivorStrategy strategy = SurvivorStrategy::kGrow;
  /// Balance slack over the survivors: every block holds at most
  /// floor((1 + eps) * ceil(n / S)) poses (S survivors). Range 0..1; default 0.03.
  double eps = 0.03;
  /// Passes of positive-gain moves of the lost poses after growing (grow). 0..100; default 4.
  int refinement_passes = 4;
  /// Partitioner preset and seed of the fresh strategy.
  PartitionPreset preset = PartitionPreset::kEco;
  std::uint64_t seed = 1;
  /// Throws InputError naming the bad field.
  void validate() const;
};

struct SurvivorRepartitionResult {
  std::vector<int> survivors;  ///< Old agent ids still running, ascending (S of them).
  std::vector<int> owner;      ///< Per pose: the survivor (old agent id) that now owns it.
  /// Per pose: the survivor's index in `survivors` (0..S-1): a dense block id for core's
  /// layout and round protocol, which number agents 0..S-1.
  std::vector<int> block;
  std::size_t lost_poses = 0;      ///< Poses the lost agents owned.
  std::size_t moved_poses = 0;     ///< Poses whose owner changed (lost ones included).
  std::size_t max_block_size = 0;  ///< The balance bound used.
  PartitionMetrics metrics;        ///< Of `block` over the S survivors.
  double time_ms = 0.0;
};

/// New owners for the survivors after agents `lost` (ids in 0..num_agents-1, at least one, not
/// all) are gone. `old_owner[v]` is the agent of pose v before the loss (0..num_agents-1).
/// Deterministic: the same inputs give the same result. Every pose ends up with a survivor;
/// the balance bound holds whenever the survivors' own blocks already satisfy it (they do when
/// the old assignment met the bound for N agents, as the bound for S < N agents is larger).
/// Throws InputError on an owner array of the wrong length or with ids out of range, a lost id
/// out of range, no lost agent, or no survivor.
SurvivorRepartitionResult repartition_for_survivors(const GraphStructure& graph,
                                                    const std::vector<int>& old_owner,
                                                    int num_agents, const std::vector<int>& lost,
                                                    const SurvivorRepartitionOptions& options = {});

}  // namespace tessera
