#pragma once
// Internal: balance bounds that force one block to be light.
//
// The best partitions of the benchmark graphs often have one block well below the average and
// the others at the bound (the reference paper's rim 2100 2096 1867 2032 2100, intel
// 253 247 253 253 222, ais2klinik 3113 3113 2692 3113 3084). A search under the uniform bound
// rarely walks into such shapes: every step towards them first needs room in a full block.
// Building a partition under bounds where one block must stay light starts the search there.

#include <vector>

#include "partition/work_graph.hpp"

namespace tessera::partition_detail {

/// Bounds equal to `ub` except for `block`, whose bound becomes
/// max(fraction x total / k, total - (sum of the other bounds) + margin), never above ub[block]
/// (margin = 1 % of the average block weight, at least 1, so that the bounds still leave room
/// to balance on coarse levels). Every partition that respects the result respects `ub`.
/// Requires 0 <= block < k = ub.size() and sum(ub) >= total.
std::vector<long long> light_block_bounds(const std::vector<long long>& ub, long long total,
                                          int block, double fraction);

/// Draws a light block and its weight fraction for `part` (the lightest block of `part` with
/// probability 1/2, else a uniformly random block; fraction uniform in [min_fraction,
/// max_fraction]) and returns light_block_bounds for them.
std::vector<long long> random_light_bounds(const WorkGraph& g, const std::vector<int>& part,
                                           const std::vector<long long>& ub, double min_fraction,
                                           double max_fraction, Rng& rng);

}  // namespace tessera::partition_detail
