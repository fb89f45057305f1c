#include "structure_graphs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tessera/partition/partition_metrics.hpp>
#include <utility>

namespace tessera::test {

GraphStructure grid_structure(std::size_t w, std::size_t h) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t y = 0; y < h; ++y)
    for (std::size_t x = 0; x < w; ++x) {
      if (x + 1 < w) pairs.emplace_back(y * w + x, y * w + x + 1);
      if (y + 1 < h) pairs.emplace_back(y * w + x, (y + 1) * w + x);
    }
  return make_graph_structure(w * h, pairs, "grid");
}

GraphStructure grid_with_chords(std::size_t w, std::size_t h, unsigned seed) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t y = 0; y < h; ++y)
    for (std::size_t x = 0; x < w; ++x) {
      if (x + 1 < w) pairs.emplace_back(y * w + x, y * w + x + 1);
      if (y + 1 < h) pairs.emplace_back(y * w + x, (y + 1) * w + x);
    }
  std::mt19937 gen(seed);
  for (std::size_t e = 0; e < w * h / 4; ++e) {
    const std::size_t v = gen() % (w * h);
    const std::size_t u = (v + 1 + gen() % 3 + (gen() % 3) * w) % (w * h);
    if (u != v) pairs.emplace_back(v, u);
  }
  return make_graph_structure(w * h, pairs, "grid+chords");
}

std::vector<long long> uniform_bounds(const GraphStructure& structure, int k, double eps) {
  return std::vector<long long>(static_cast<std::size_t>(k), static_cast<long long>(max_block_size(
                                                                 structure.num_vertices, k, eps)));
}

partition_detail::CycleParams small_graph_cycle(long long ub) {
  partition_detail::CycleParams cp;
  cp.coarsening.stop_vertices = 100;
  cp.coarsening.max_vertex_weight = static_cast<int>(std::max<long long>(2, ub / 30));
  cp.coarsening.label_propagation_rounds = 3;
  cp.initial.repeats = 4;
  cp.initial.fm = cp.fm;
  cp.use_flow = true;
  cp.flow_levels = 2;
  return cp;
}

partition_detail::EvolutionParams small_search(long long ub) {
  partition_detail::EvolutionParams p;
  p.population = 3;
  p.generations = 12;
  p.mutation_rate = 0.5;
  p.cycle = small_graph_cycle(ub);
  return p;
}

void expect_blocks_within(const partition_detail::WorkGraph& g, const std::vector<int>& part, int k,
                          const std::vector<long long>& ub) {
  ASSERT_EQ(part.size(), static_cast<std::size_t>(g.n));
  for (int b : part) {
    ASSERT_GE(b, 0);
    ASSERT_LT(b, k);
  }
  const std::vector<long long> w = partition_detail::block_weights(g, part, k);
  for (int b = 0; b < k; ++b) EXPECT_LE(w[b], ub[b]) << "block " << b;
}

}  // namespace tessera::test
