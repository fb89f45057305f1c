#pragma once
// Internal: max-flow/min-cut refinement between pairs of adjacent blocks (in the spirit of
// KaHIP's flow refinement). For blocks A and B it grows a corridor on both sides of their common
// boundary, small enough that any reassignment inside it keeps both blocks within their
// bounds, and replaces the A–B boundary by a minimum cut through the corridor. Unlike FM it can
// move many vertices at once, which moves boundaries out of local minima.

#include <vector>

#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

struct FlowParams {
  int rounds = 2;      ///< Sweeps over all adjacent block pairs (stops early without gain).
  double alpha = 8.0;  ///< First corridor size, in units of the balance slack; halved on failure.
};

/// Improves `part` in place; never increases the cut or breaks a bound. Returns the new cut.
/// `known_cut`: the cut of `part` when the caller has it, -1 = not known.
long long flow_refine(const WorkGraph& g, int k, std::vector<int>& part,
                      const std::vector<long long>& ub, const FlowParams& params, Rng& rng,
                      long long known_cut = -1);

}  // namespace tessera::partition_detail
