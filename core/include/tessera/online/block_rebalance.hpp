#pragma once
// The partition follows the graph: blocks start aligned with the robots (each agent owns its
// robot's poses) and change in two ways, both from the current owners and by border poses only:
//  - balance: when the graph grows unevenly (a robot that joins late, one that moves faster),
//    border poses of an over-full block move to a lighter neighbouring block;
//  - cut: when the measurements between blocks pass a fraction of all measurements (robots
//    whose trajectories cross the same places: city10000's five robot blocks cut 8,369 of its
//    20,687 measurements), a k-way Fiduccia-Mattheyses refinement moves border poses to the
//    block that holds more of their measurements, within the balance bounds, and keeps the
//    prefix of its moves that cut the fewest measurements (the shortest such prefix).
// Moving only border poses refines the current partition from where it is: few poses move,
// and a moved pose joins a block it already had a measurement into.

#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct RebalanceOptions {
  bool enabled = true;
  /// A block may hold up to (1 + slack) ceil(n / N) poses before poses move out of it and,
  /// with the cut refinement on, no fewer than (1 - slack) floor(n / N) (rebalance_blocks).
  /// >= 0.
  double slack = 0.2;
  /// ... and only when it is at least this many poses over that bound (small graphs at the
  /// start of a mission are not worth moving poses for). The cut refinement never fills a block
  /// beyond (1 + slack) ceil(n / N) + min_excess either.
  std::size_t min_excess = 10;
  /// Cut refinement (needs `enabled`): runs when more than `cut_fraction` of the measurements
  /// join poses of two blocks. In [0, 1]; 1 = never. city10000 replayed by 5 robots, a step
  /// every 0.1 s of stream: the cut ends at 478 of 20,687 measurements (156 re-partitions,
  /// 3,961 poses moved) against 8,369 for the robots' blocks, and the steps take 34,354 CG
  /// iterations against 103,615 (docs/online.md, "The partition follows the graph"). The cut
  /// then hovers near the threshold; 0.03 / 0.05 end at 568 / 758 with 2,893 / 1,904 poses
  /// moved (replays of the structure alone).
  double cut_fraction = 0.02;
  /// Refinement passes at most (each pass moves a pose at most once and keeps its best
  /// prefix; the next pass starts from there). >= 1.
  int max_passes = 8;
  /// A pass stops after this many moves in a row that do not improve on its best cut (the
  /// negative-gain moves that let a chain of poses cross over). >= 1.
  std::size_t pass_patience = 64;
  /// New poses (ids past the previous call's) join the block holding most of their
  /// measurements to older poses (their robot's block on a tie it is part of, or when they
  /// have none) instead of always their robot's block. Only with the cut refinement on
  /// (cut_fraction < 1): otherwise blocks stay the robots'.
  bool place_by_links = true;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

struct RebalanceResult {
  std::size_t moved = 0;                              ///< Poses that changed block.
  std::size_t largest_before = 0, largest_after = 0;  ///< Largest block's pose count.
  std::size_t smallest_after = 0;                     ///< Smallest block's pose count.
  /// Single-pose moves along chains of blocks that brought blocks within the bounds (a pose
  /// passed along a chain counts once per hop); 0 without the cut refinement.
  std::size_t chain_moves = 0;
  /// Of `moved`: poses the cut refinement moved (the rest are balance moves).
  std::size_t cut_moved = 0;
  /// Measurements between two blocks before and after the call (computed only when the
  /// refinement is on; 0 otherwise).
  std::size_t cut_before = 0, cut_after = 0;
  bool refined = false;  ///< The cut refinement ran (it may have moved nothing).
};

/// Moves poses of blocks above the bound, one border pose at a time (from the largest such
/// block that has one), to the lightest neighbouring block that is at least two poses
/// lighter, until every block is within the bound or no such move is left. Poses do not pass
/// through a block in one call (no cascade): a full block between an over-full one and a light
/// one stops the move. With the cut refinement on (cut_fraction < 1), then the bounds by
/// chains: every block still above the upper bound `floor((1 + slack) ceil(n / N) +
/// min_excess)` gives poses to the nearest block below it, and every block under the floor
/// `floor((1 - slack) floor(n / N))` (at least 1) takes poses from the nearest block above it,
/// each pose passing along the shortest chain of blocks linked by measurements, one border
/// pose a hop, so the blocks in between keep their size. Then, when the cut is above
/// options.cut_fraction, refine_cut, which keeps both bounds. So after a call with the
/// refinement on, a block is out of the bounds only when no chain of measurements links it to a
/// block that could take (give) a pose: a piece of the graph whose blocks are all at or past
/// the bound (a robot that has met no other). `owner[k]` in 0..num_blocks-1; no block becomes
/// empty.
RebalanceResult rebalance_blocks(const PoseGraph& graph, std::vector<int>& owner, int num_blocks,
                                 const RebalanceOptions& options);

/// The cut refinement alone (rebalance_blocks calls it with `bound` = floor((1 + slack)
/// ceil(n / N) + min_excess) and `lower` = floor((1 - slack) floor(n / N))): passes of
/// single-pose moves, each the border pose whose move to a block it has a measurement into
/// removes the most cut measurements (lowest id on ties; the target on ties: the lighter, then
/// the lower block), into blocks below `bound` poses, out of blocks above `lower` poses (and
/// never emptying a block); a pass moves a pose at most once,
/// stops after options.pass_patience moves without a new best and is rolled back to its best
/// prefix (the shortest on ties). Passes repeat while they cut fewer measurements, up to
/// options.max_passes. Returns the poses whose block changed; deterministic.
std::size_t refine_cut(const PoseGraph& graph, std::vector<int>& owner, int num_blocks,
                       std::size_t bound, std::size_t lower, const RebalanceOptions& options);

/// Measurements whose poses lie in two different blocks.
std::size_t cut_measurements(const PoseGraph& graph, const std::vector<int>& owner);

/// Blocks of the new poses [owner.size(), graph.num_poses), appended to `owner` in id order:
/// `robot_block[k - owner.size()]` (their robot's block) unless options.place_by_links and the
/// cut refinement are on, in which case a new pose joins the block holding most of its
/// measurements to poses that already have one (its robot's block if that is among the most,
/// else the lowest such block; its robot's block when it has none, or when that block has no
/// pose yet: a robot that joins gets a block of its own).
void assign_new_poses(const PoseGraph& graph, std::vector<int>& owner,
                      const std::vector<int>& robot_block, const RebalanceOptions& options);

}  // namespace tessera
