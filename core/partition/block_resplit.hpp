#pragma once
// Internal: a large-neighbourhood step after the search — keep a few blocks of the best
// partition and search the rest of the graph again, from scratch, as a smaller partitioning
// problem.
//
// The memetic search settles into one global arrangement of the blocks, and on some graphs the
// arrangement decides the cut. rim's best partitions share one light block (1867 poses, 49 cut
// edges) but arrange the other four blocks differently: our seed-1 246 and seed-3 243 keep that
// block identical and differ by 1792 poses among the rest, which no local operator (FM, flows,
// V-cycles, combines) moves. torus3D's 242 and 240 share two strip blocks and differ in how the
// remaining three blocks split the rest. With the kept blocks fixed, every edge between them and
// the rest is cut whatever the rest does, so the remaining problem is exact: split the subgraph
// induced by the other blocks into that many blocks under the same bound, minimising only the
// edges inside it. A fresh search there (a small population of its own) is not tied to the old
// arrangement of those blocks (rim: holding the light block and searching the rest with
// `strong`'s effort gave 243 on 2 of 4 seeds; torus3D: holding its two strips, 240 on 2 of 4).
// Keeping the two most separable blocks did better than keeping one on the small benchmark
// graphs (torus3D seeds 1-8: keep 1 never improved, keep 2 on seeds 1, 7, 8).

#include <string>
#include <vector>

#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct EvolutionParams;

struct BlockResplitOptions {
  /// Sub-searches, each with its own generator and thread (at most 2 threads). 0 = off.
  /// Range 0..8.
  int searches = 0;
  /// Blocks each sub-search keeps: those with the fewest cut edges (ties: lower block id), at
  /// most k - 2 (at least two blocks are split again; nothing happens for k < 3). Range 1..62.
  int kept = 2;
  /// Individuals of each sub-search's population. Range 2..64.
  int population = 4;
  /// Combine / mutation steps of each sub-search, as a share of the full search's
  /// (EvolutionParams::generations), at least 1. Range (0, 1].
  double budget = 0.3;
  /// Only for partitions into at most this many blocks (with many blocks the rest is almost
  /// the whole problem again and the step budgets are small). Range 2..64.
  int max_parts = 8;
  /// Only when every kept block is clearly separable: its cut edges at most this share of the
  /// mean block cut (2 x cut / k). A block whose boundary is much cheaper than the others' is
  /// likely a block of every good partition (rim's light block: 49 cut edges, mean 98); in a
  /// mesh every block's boundary costs about the same (grid3D: 0.92) and keeping one is a
  /// guess. 0 = no condition. Range: 0 or (0, 1].
  double max_cut_ratio = 0.0;

  /// Throws InputError naming the first field out of range.
  void validate() const;
};

struct BlockResplitResult {
  bool improved = false;  ///< Whether `part` was replaced.
  long long cut = 0;      ///< The cut of `part` on return.
  std::string detail;     ///< Per sub-search: blocks kept, its best total cut, thread CPU.
  std::vector<double> thread_cpu_ms;  ///< Per worker thread.
};

/// Runs params.resplit.searches sub-searches (the memetic search of `params` with the
/// population and step budget above, one island, no polish / spectral layouts / re-split) on
/// the blocks of `part` (balanced under ub) that each one does not keep; each result is merged
/// into `part`, V-cycled on the whole graph, and the best of them (ties: the lower sub-search)
/// replaces `part` when its cut is strictly lower. Each sub-search draws from its own generator
/// seeded from `rng` (not advanced), so the result does not depend on thread timing.
BlockResplitResult block_resplit(const WorkGraph& g, int k, const std::vector<long long>& ub,
                                 std::vector<int>& part, const EvolutionParams& params,
                                 const Rng& rng);

}  // namespace tessera::partition_detail
