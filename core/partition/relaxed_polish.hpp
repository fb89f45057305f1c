#pragma once
// Internal: refinement of a finished partition through a briefly relaxed balance bound.
//
// The best partitions often have several blocks exactly at the bound (rim: 2100 2100 2096 of
// 2100). A better cut can then be a few small moves away that only work together: a cluster
// moves into a full block while that block hands single vertices on to another one (rim: 247 ->
// 243 by 10 vertices in such a chain). FM moves one vertex at a time and never lets a block
// exceed its bound, and the flow corridors shrink to nothing when both blocks are at the bound,
// so neither can make such a chain. With the bound raised by a few vertices both can move the
// cluster; rebalancing then removes the excess where it costs least, and FM plus flows under the
// real bound clean up.

#include <vector>

#include "partition/multilevel.hpp"

namespace tessera::partition_detail {

struct RelaxedPolishOptions {
  /// Relax / repair rounds, each from the best partition so far (ties replace it, so equal-cut
  /// partitions are explored). 0 = off.
  int rounds = 0;
  /// Each round raises every bound by a fraction of it drawn from [min_relax, max_relax]
  /// (rim: 2100 -> +4..63 vertices); 0 < min_relax <= max_relax <= 0.5.
  double min_relax = 0.002;
  double max_relax = 0.03;

  /// Throws InputError naming the first field out of range.
  void validate() const;
};

/// Improves `part` (balanced under ub) by options.rounds relax / repair rounds using the FM and
/// flow parameters of `cycle` (each round: FM, flows and FM under the raised bounds, rebalance,
/// then FM, flows and FM under ub; flow corridors alternate between alpha and 2 alpha). Keeps a
/// round's result only when its cut is no worse, so the cut never increases and the result
/// stays within ub. Returns the final cut.
long long relaxed_polish(const WorkGraph& g, int k, const std::vector<long long>& ub,
                         std::vector<int>& part, const RelaxedPolishOptions& options,
                         const CycleParams& cycle, Rng& rng);

}  // namespace tessera::partition_detail
