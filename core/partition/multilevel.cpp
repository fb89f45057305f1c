#include "partition/multilevel.hpp"

#include <algorithm>
#include <cstdlib>

namespace tessera::partition_detail {
std::vector<long long> level_bounds(const WorkGraph& g, const std::vector<long long>& ub) {
  const int heaviest = g.vw.empty() ? 1 : *std::max_element(g.vw.begin(), g.vw.end());
  std::vector<long long> relaxed = ub;
#ifdef TESSERA_PARTITION_TUNING
  if (std::getenv("T_NORELAX")) return relaxed;
#endif
  for (auto& b : relaxed) b += heaviest - 1;
  return relaxed;
}

long long refine_level(const WorkGraph& g, int k, std::vector<int>& part,
                       const std::vector<long long>& ub_fine, const CycleParams& params, Rng& rng,
                       bool flow) {
  const std::vector<long long> ub = level_bounds(g, ub_fine);
  rebalance(g, k, part, ub);
  long long cut = kway_fm(g, k, part, ub, params.fm, rng);
  if (params.use_flow && flow) {
    // Both return the exact cut, so the next step need not scan the graph for it again.
    const long long after = flow_refine(g, k, part, ub, params.flow, rng, cut);
    if (after < cut) cut = kway_fm(g, k, part, ub, params.fm, rng, after);
  }
  return cut;
}

namespace {

std::vector<long long> coarse_bounds(const std::vector<long long>& ub, const CycleParams& params) {
  if (params.coarse_relax <= 0.0) return ub;
  std::vector<long long> relaxed = ub;
  for (auto& b : relaxed)
    b = static_cast<long long>(static_cast<double>(b) * (1.0 + params.coarse_relax));
  return relaxed;
}

// Projects the coarsest partition down level by level, rebalancing and refining on each.
std::vector<int> uncoarsen(const WorkGraph& fine, const Hierarchy& h, std::vector<int> part, int k,
                           const std::vector<long long>& ub, const CycleParams& params, Rng& rng,
                           CycleStats* stats) {
  const std::vector<long long> ub_coarse = coarse_bounds(ub, params);
  for (int level = static_cast<int>(h.coarse.size()) - 1; level >= 0; --level) {
    const WorkGraph& g = level > 0 ? h.coarse[level - 1] : fine;
    const std::vector<int>& map = h.maps[level];
    std::vector<int> finer(static_cast<std::size_t>(g.n));
    for (int v = 0; v < g.n; ++v) finer[v] = part[map[v]];
    part.swap(finer);
    const long long cut = refine_level(g, k, part, level > 0 ? ub_coarse : ub, params, rng,
                                       level <= params.flow_levels);
    if (stats && level == 0) stats->cut = cut;
  }
  if (stats && h.coarse.empty()) stats->cut = edge_cut(fine, part);
  return part;
}

}  // namespace

std::vector<int> multilevel_partition(const WorkGraph& g, int k, const std::vector<long long>& ub,
                                      const CycleParams& params, Rng& rng, CycleStats* stats) {
  const Hierarchy h = coarsen(g, nullptr, params.coarsening, rng);
  const WorkGraph& top = h.top(g);
  const std::vector<long long> ub_top = h.coarse.empty() ? ub : coarse_bounds(ub, params);
  std::vector<int> part = initial_partition(top, k, level_bounds(top, ub_top), params.initial, rng);
  if (stats) {
    stats->levels = static_cast<int>(h.coarse.size());
    stats->coarsest_vertices = top.n;
    stats->coarsest_cut = edge_cut(top, part);
  }
  return uncoarsen(g, h, std::move(part), k, ub, params, rng, stats);
}

std::vector<int> guided_cycle(const WorkGraph& g, int k, const std::vector<long long>& ub,
                              const std::vector<int>& label, const std::vector<int>& start,
                              const CycleParams& params, Rng& rng, CycleStats* stats) {
  const Hierarchy h = coarsen(g, &label, params.coarsening, rng);
  const WorkGraph& top = h.top(g);
  // Project `start` up to the coarsest level (constant on every cluster by construction).
  std::vector<int> part = start;
  for (const auto& map : h.maps) {
    int cn = 0;
    for (int c : map) cn = std::max(cn, c + 1);
    std::vector<int> coarse(static_cast<std::size_t>(cn));
    for (std::size_t v = 0; v < map.size(); ++v) coarse[map[v]] = part[v];
    part.swap(coarse);
  }
  refine_level(top, k, part, h.coarse.empty() ? ub : coarse_bounds(ub, params), params, rng,
               static_cast<int>(h.coarse.size()) <= params.flow_levels);
  if (stats) {
    stats->levels = static_cast<int>(h.coarse.size());
    stats->coarsest_vertices = top.n;
    stats->coarsest_cut = edge_cut(top, part);
  }
  return uncoarsen(g, h, std::move(part), k, ub, params, rng, stats);
}

}  // namespace tessera::partition_detail
