#pragma once
// The partition follows the graph: blocks start aligned with the robots (each agent owns its
// robot's poses) and, when the graph grows unevenly (a robot that joins late, one that moves
// faster), border poses of an over-full block move to a lighter neighbouring block. Moving
// only border poses (those with a measurement into the receiving block) refines the current
// partition from where it is: few poses move, the receiving block stays connected to what it
// already had, and the cut grows by at most the moved poses' other measurements.

#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct RebalanceOptions {
  bool enabled = true;
  /// A block may hold up to (1 + slack) ceil(n / N) poses before poses move out of it. >= 0.
  double slack = 0.2;
  /// ... and only when it is at least this many poses over that bound (small graphs at the
  /// start of a mission are not worth moving poses for).
  std::size_t min_excess = 10;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

struct RebalanceResult {
  std::size_t moved = 0;                              ///< Poses that changed block.
  std::size_t largest_before = 0, largest_after = 0;  ///< Largest block's pose count.
};

/// Moves poses of blocks above the bound, one border pose at a time (from the largest such
/// block that has one), to the lightest neighbouring block that is at least two poses
/// lighter, until every block is within the bound or no such move is left. Poses do not pass
/// through a block in one call (no cascade): a full block between an over-full one and a light
/// one stops the move. `owner[k]` in 0..num_blocks-1; no block becomes empty.
RebalanceResult rebalance_blocks(const PoseGraph& graph, std::vector<int>& owner, int num_blocks,
                                 const RebalanceOptions& options);

}  // namespace tessera
