// Max-flow refinement between block pairs (flow_refinement.hpp): a jagged boundary becomes the
// minimum cut through the corridor, and on irregular graphs the cut never gets worse, the
// returned cut is the partition's, the bounds hold and the same seed gives the same result.
// (The max flow inside is Boykov-Kolmogorov's search trees, formerly Dinic; the partitions must
// not depend on which maximum flow is found.)

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tessera/partition/graph_structure.hpp>

#include "partition/flow_refinement.hpp"
#include "structure_graphs.hpp"

namespace {

using namespace tessera;
using namespace tessera::partition_detail;

// A 20 x 10 grid with a diagonal (x, y)-(x + 1, y + 1) in every column gap but the one between
// columns 9 and 10, so the straight split there (10 edges) is the only minimum left-right cut
// (any other cuts every row once plus the diagonals, or rows twice). Start: two blocks of 100
// whose boundary zig-zags between columns 8 and 12 from row to row. The corridors (5
// vertices of room plus 8 x 5 of slack on each side) hold the whole zig-zag, so the flow finds
// that split.
TEST(FlowRefine, StraightensAJaggedBoundaryToTheMinimumCut) {
  const std::size_t w = 20, h = 10;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t y = 0; y < h; ++y)
    for (std::size_t x = 0; x < w; ++x) {
      if (x + 1 < w) pairs.emplace_back(y * w + x, y * w + x + 1);
      if (y + 1 < h) pairs.emplace_back(y * w + x, (y + 1) * w + x);
      if (x + 1 < w && y + 1 < h && x != 9) pairs.emplace_back(y * w + x, (y + 1) * w + x + 1);
    }
  const WorkGraph g = to_work_graph(make_graph_structure(w * h, pairs, "diagonal grid"));
  const int k = 2;
  const std::vector<long long> ub(2, 105);
  std::vector<int> part(w * h), straight(w * h);
  for (std::size_t y = 0; y < h; ++y)
    for (std::size_t x = 0; x < w; ++x) {
      part[y * w + x] = x < (y % 2 == 0 ? 8u : 12u) ? 0 : 1;
      straight[y * w + x] = x < 10 ? 0 : 1;
    }
  const long long start = edge_cut(g, part);
  ASSERT_EQ(edge_cut(g, straight), 10);
  ASSERT_GT(start, 10);
  Rng rng(1);
  const long long cut = flow_refine(g, k, part, ub, FlowParams{}, rng);
  EXPECT_EQ(cut, 10) << "from " << start;
  EXPECT_EQ(part, straight);
  test::expect_blocks_within(g, part, k, ub);
}

// Grids with random chords, 2-4 blocks made of vertical bands whose boundaries are randomly
// frayed: the result is never worse than the start, the returned cut is exact, every block stays
// within its bound, and the same seed gives the same partition; most starts improve.
TEST(FlowRefine, NeverWorseExactWithinTheBoundsAndDeterministic) {
  int improved = 0, cases = 0;
  for (unsigned seed = 1; seed <= 12; ++seed)
    for (int k = 2; k <= 4; ++k) {
      const std::size_t w = 30, h = 12;
      const GraphStructure s = test::grid_with_chords(w, h, seed);
      const WorkGraph g = to_work_graph(s);
      const std::vector<long long> ub = test::uniform_bounds(s, k, 0.05);
      std::mt19937 gen(seed * 10 + static_cast<unsigned>(k));
      std::vector<int> part(w * h);
      for (std::size_t y = 0; y < h; ++y)
        for (std::size_t x = 0; x < w; ++x) {
          // Band of column x, moved by one column at random near the band edges.
          const int shift = static_cast<int>(gen() % 3) - 1;
          const int col = std::clamp(static_cast<int>(x) + shift, 0, static_cast<int>(w) - 1);
          part[y * w + x] = col * k / static_cast<int>(w);
        }
      // Keep only starts within the bounds (the frayed bands are near-balanced).
      const std::vector<long long> bw = block_weights(g, part, k);
      bool within = true;
      for (int b = 0; b < k; ++b) within = within && bw[b] <= ub[b];
      if (!within) continue;
      ++cases;
      const long long before = edge_cut(g, part);
      std::vector<int> once = part, twice = part;
      Rng r1(seed), r2(seed);
      const long long cut = flow_refine(g, k, once, ub, FlowParams{}, r1);
      flow_refine(g, k, twice, ub, FlowParams{}, r2);
      EXPECT_LE(cut, before) << "seed " << seed << " k " << k;
      EXPECT_EQ(cut, edge_cut(g, once)) << "seed " << seed << " k " << k;
      test::expect_blocks_within(g, once, k, ub);
      EXPECT_EQ(once, twice) << "seed " << seed << " k " << k;
      if (cut < before) ++improved;
    }
  EXPECT_GE(cases, 20);
  EXPECT_GE(improved, cases / 2);
}

}  // namespace
