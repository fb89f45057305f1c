#pragma once
// Internal: partitions the coarsest graph of the hierarchy from scratch.

#include <vector>

#include "partition/kway_refinement.hpp"
#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct InitialParams {
  int repeats = 2;  ///< Independent recursive-bisection runs; the best k-way result is kept.
  /// When > 0, the number of runs shrinks with the size of the graph: clamp(round(repeat_budget
  /// / n), min_repeats, repeats). Many blocks make the coarsest graph large (coarse vertices stay
  /// below lmax/30, i.e. ~40 k vertices for k blocks), and every run costs ~ n log k.
  int repeat_budget = 0;
  int min_repeats = 1;      ///< Lower end of that range (>= 1).
  int bisection_tries = 4;  ///< Greedy-growing + 2-way FM tries per bisection; the best is kept.
  double eps = 0.03;        ///< Slack of each bisection around its target weight.
  FmParams fm;              ///< Refinement used for the bisections and the final k-way result.
};

/// Recursive bisection by greedy graph growing (grow one side from a random vertex, always
/// taking the vertex that adds the least cut) and 2-way FM, then k-way rebalancing and FM
/// against ub. Returns the best partition found (feasible ones first, then the smaller cut).
std::vector<int> initial_partition(const WorkGraph& g, int k, const std::vector<long long>& ub,
                                   const InitialParams& params, Rng& rng);

}  // namespace tessera::partition_detail
