#pragma once
// Internal: one multilevel cycle (coarsen, partition the coarsest graph, project and refine back
// up), used fresh, as a V-cycle on an existing partition, or to combine two partitions.

#include <vector>

#include "partition/coarsening.hpp"
#include "partition/flow_refinement.hpp"
#include "partition/initial_partitioning.hpp"
#include "partition/kway_refinement.hpp"
#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct CycleParams {
  CoarseningParams coarsening;
  InitialParams initial;
  FmParams fm;
  bool use_flow = false;  ///< Add max-flow refinement between block pairs...
  int flow_levels = 64;   ///< ...on this many of the finest levels (0 = the input graph only).
  FlowParams flow;
  /// Coarse levels (all but the input graph) use bounds (1 + coarse_relax) x ub: a looser
  /// balance there lets the search pass through partitions the tight bound forbids (e.g. one
  /// light block and the others at the bound); the input graph is rebalanced and refined under
  /// the exact ub. 0 = the same bound everywhere.
  double coarse_relax = 0.0;
};

/// The bounds used on a level whose heaviest vertex weighs w: ub + w - 1. Coarse levels may
/// overshoot by less than one vertex (otherwise a tight bound may be unreachable with heavy
/// vertices); on the input graph (unit weights) they are exactly ub.
std::vector<long long> level_bounds(const WorkGraph& g, const std::vector<long long>& ub);

/// The refinement applied on every level: rebalance, FM, then (optionally) flow refinement
/// followed by another FM round when the flows found something. Returns the cut.
long long refine_level(const WorkGraph& g, int k, std::vector<int>& part,
                       const std::vector<long long>& ub, const CycleParams& params, Rng& rng,
                       bool flow = true);

struct CycleStats {
  int levels = 0;  ///< Coarse levels built.
  int coarsest_vertices = 0;
  long long coarsest_cut = 0;  ///< Cut right after initial partitioning (or projection).
  long long cut = 0;           ///< Final cut.
};

/// A fresh multilevel partition of g into k blocks with block weights <= ub.
std::vector<int> multilevel_partition(const WorkGraph& g, int k, const std::vector<long long>& ub,
                                      const CycleParams& params, Rng& rng,
                                      CycleStats* stats = nullptr);

/// A V-cycle that keeps `start` representable on every level: coarsening only contracts
/// vertices with the same `label` (e.g. the block of `start`, or a pair of blocks of two parents
/// for combine), the coarsest graph starts from `start`, and FM refines on every level. The
/// result is never worse than `start` if `start` is balanced and params.coarse_relax is 0 (with
/// a relaxed coarse bound the input graph's repair may cost cut: callers compare).
std::vector<int> guided_cycle(const WorkGraph& g, int k, const std::vector<long long>& ub,
                              const std::vector<int>& label, const std::vector<int>& start,
                              const CycleParams& params, Rng& rng, CycleStats* stats = nullptr);

}  // namespace tessera::partition_detail
