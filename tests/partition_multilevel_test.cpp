// The multilevel partitioner: known optimal cuts on small graphs, validity and balance for
// N = 2..64, determinism for a fixed seed, and option errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partition_metrics.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/util/input_error.hpp>

#include "partition/evolutionary.hpp"
#include "partition/light_block.hpp"
#include "partition/multilevel.hpp"
#include "structure_graphs.hpp"

namespace {

using namespace tessera;
using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;

const PartitionPreset kMultilevel[] = {PartitionPreset::kFast, PartitionPreset::kEco,
                                       PartitionPreset::kStrong, PartitionPreset::kHighest};

GraphStructure path_graph(std::size_t n) {
  Pairs p;
  for (std::size_t v = 0; v + 1 < n; ++v) p.emplace_back(v, v + 1);
  return make_graph_structure(n, p, "path");
}

GraphStructure grid_graph(std::size_t w, std::size_t h) {
  return test::grid_structure(w, h);
}

// Two cliques of size s joined by one edge (between vertex 0 and vertex s).
GraphStructure two_cliques(std::size_t s) {
  Pairs p;
  for (std::size_t c = 0; c < 2; ++c)
    for (std::size_t a = 0; a < s; ++a)
      for (std::size_t b = a + 1; b < s; ++b) p.emplace_back(c * s + a, c * s + b);
  p.emplace_back(0, s);
  return make_graph_structure(2 * s, p, "cliques");
}

// A pose-graph-like structure: an odometry chain wandering on a plane, plus loop closures
// between poses that come close again, and some repeated (parallel) measurements.
GraphStructure pose_like_graph(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> turn(-0.6, 0.6);
  std::vector<double> x(n), y(n);
  double heading = 0.0;
  for (std::size_t v = 1; v < n; ++v) {
    heading += turn(rng);
    x[v] = x[v - 1] + std::cos(heading);
    y[v] = y[v - 1] + std::sin(heading);
  }
  Pairs p;
  for (std::size_t v = 0; v + 1 < n; ++v) p.emplace_back(v, v + 1);
  for (std::size_t v = 0; v < n; v += 3)
    for (std::size_t u = 0; u + 20 < v; u += 7)
      if (std::hypot(x[u] - x[v], y[u] - y[v]) < 1.5) p.emplace_back(u, v);
  for (std::size_t v = 0; v + 1 < n; v += 17) p.emplace_back(v + 1, v);  // parallel, backward
  return make_graph_structure(n, p, "pose-like");
}

void expect_valid(const GraphStructure& g, const PartitionResult& r, int parts, double eps) {
  ASSERT_EQ(r.assignment.size(), g.num_vertices);
  for (int b : r.assignment) {
    ASSERT_GE(b, 0);
    ASSERT_LT(b, parts);
  }
  const PartitionMetrics m = compute_partition_metrics(g, r.assignment, parts);
  EXPECT_LE(m.max_block, max_block_size(g.num_vertices, parts, eps));
  EXPECT_EQ(m.max_block, r.metrics.max_block);
  EXPECT_EQ(m.cut_edges, r.metrics.cut_edges);
  EXPECT_EQ(r.max_block_size, max_block_size(g.num_vertices, parts, eps));
}

PartitionResult run(const GraphStructure& g, int parts, PartitionPreset preset, double eps = 0.03,
                    std::uint64_t seed = 1) {
  PartitionOptions o;
  o.parts = parts;
  o.preset = preset;
  o.eps = eps;
  o.seed = seed;
  return partition_graph(g, o);
}

TEST(Partitioner, PathHasOptimalCut) {
  const GraphStructure g = path_graph(200);
  for (auto preset : kMultilevel)
    for (int parts : {2, 5, 8}) {
      const auto r = run(g, parts, preset);
      expect_valid(g, r, parts, 0.03);
      // fast (one multilevel run, no V-cycle) may leave one extra cut on the tightest cases.
      EXPECT_LE(r.metrics.cut_edges,
                static_cast<std::size_t>(parts - 1) + (preset == PartitionPreset::kFast ? 1u : 0u))
          << preset_name(preset) << " N=" << parts;
    }
}

TEST(Partitioner, GridBisectionCutsOneColumn) {
  // 16 x 10 grid, 2 blocks of 80 (eps 0): the optimum cuts the 10 edges of one column. The
  // cheap presets must come close, the strong ones must find it.
  const GraphStructure g = grid_graph(16, 10);
  for (auto preset : kMultilevel) {
    const auto r = run(g, 2, preset, 0.0);
    expect_valid(g, r, 2, 0.0);
    if (preset == PartitionPreset::kStrong || preset == PartitionPreset::kHighest)
      EXPECT_EQ(r.metrics.cut_edges, 10u) << preset_name(preset);
    else
      EXPECT_LE(r.metrics.cut_edges, 14u) << preset_name(preset);
  }
  // 20 x 20 grid into 4 blocks of about 100: optimum 40 (two straight cuts).
  const GraphStructure g4 = grid_graph(20, 20);
  for (auto preset : {PartitionPreset::kStrong, PartitionPreset::kHighest}) {
    const auto r = run(g4, 4, preset, 0.03);
    expect_valid(g4, r, 4, 0.03);
    EXPECT_EQ(r.metrics.cut_edges, 40u) << preset_name(preset);
  }
}

TEST(Partitioner, TwoCliquesSplitAtTheBridge) {
  const GraphStructure g = two_cliques(12);
  for (auto preset : kMultilevel) {
    const auto r = run(g, 2, preset, 0.0);
    expect_valid(g, r, 2, 0.0);
    EXPECT_EQ(r.metrics.cut_edges, 1u) << preset_name(preset);
    EXPECT_EQ(r.metrics.cut_pairs, 1u);
  }
}

TEST(Partitioner, ValidAndBalancedForEveryBlockCount) {
  const GraphStructure g = pose_like_graph(1200, 7);
  std::size_t multilevel_total = 0, sequential_total = 0;
  for (int parts = 2; parts <= 64; ++parts) {
    const auto preset = parts % 4 ? PartitionPreset::kFast : PartitionPreset::kEco;
    const auto r = run(g, parts, preset);
    expect_valid(g, r, parts, 0.03);
    const auto seq = run(g, parts, PartitionPreset::kSequential, 0.0);
    expect_valid(g, seq, parts, 0.0);
    if (parts <= 16) {
      multilevel_total += r.metrics.cut_edges;
      sequential_total += seq.metrics.cut_edges;
    }
  }
  // The test graph is nearly a path, where contiguous ranges are good; still the multilevel
  // partitions must win overall for moderate N.
  EXPECT_LT(multilevel_total, sequential_total);
  const GraphStructure small = pose_like_graph(400, 9);
  for (int parts : {3, 16, 64})
    for (auto preset : {PartitionPreset::kStrong, PartitionPreset::kHighest})
      expect_valid(small, run(small, parts, preset), parts, 0.03);
}

TEST(Partitioner, TightAndLooseBalance) {
  const GraphStructure g = pose_like_graph(1001, 3);
  for (double eps : {0.0, 0.01, 0.5, 1.0}) {
    const auto r = run(g, 7, PartitionPreset::kEco, eps);
    expect_valid(g, r, 7, eps);
  }
}

TEST(Partitioner, OneBlockAndAsManyBlocksAsVertices) {
  const GraphStructure g = pose_like_graph(300, 5);
  const auto one = run(g, 1, PartitionPreset::kHighest);
  EXPECT_EQ(one.metrics.cut_edges, 0u);
  EXPECT_TRUE(
      std::all_of(one.assignment.begin(), one.assignment.end(), [](int b) { return b == 0; }));
  const GraphStructure tiny = path_graph(9);
  for (auto preset : kMultilevel) {
    const auto r = run(tiny, 9, preset, 0.0);
    expect_valid(tiny, r, 9, 0.0);
    EXPECT_EQ(r.metrics.cut_edges, 8u);
  }
}

TEST(Partitioner, DisconnectedGraph) {
  // Four separate paths of 50: 4 blocks can cut nothing.
  Pairs p;
  for (std::size_t c = 0; c < 4; ++c)
    for (std::size_t v = 0; v + 1 < 50; ++v) p.emplace_back(c * 50 + v, c * 50 + v + 1);
  const GraphStructure g = make_graph_structure(200, p, "paths");
  for (auto preset : kMultilevel) {
    const auto r = run(g, 4, preset, 0.0);
    expect_valid(g, r, 4, 0.0);
    EXPECT_EQ(r.metrics.cut_edges, 0u) << preset_name(preset);
  }
}

TEST(Partitioner, DeterministicForAFixedSeed) {
  const GraphStructure g = pose_like_graph(2000, 11);
  for (auto preset : kMultilevel) {
    const auto a = run(g, 5, preset, 0.03, 42);
    const auto b = run(g, 5, preset, 0.03, 42);
    EXPECT_EQ(a.assignment, b.assignment) << preset_name(preset);
  }
}

TEST(Partitioner, StrongerPresetsAreNotWorseOnAverage) {
  const GraphStructure g = pose_like_graph(2000, 13);
  double fast = 0, highest = 0;
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    fast += static_cast<double>(run(g, 6, PartitionPreset::kFast, 0.03, seed).metrics.cut_edges);
    highest +=
        static_cast<double>(run(g, 6, PartitionPreset::kHighest, 0.03, seed).metrics.cut_edges);
  }
  EXPECT_LE(highest, fast);
}

TEST(Partitioner, TraceDescribesThePhases) {
  const GraphStructure g = pose_like_graph(800, 2);
  const auto r = run(g, 4, PartitionPreset::kStrong);
  ASSERT_FALSE(r.trace.empty());
  EXPECT_EQ(r.trace.back().cut, static_cast<long long>(r.metrics.cut_edges));
  EXPECT_GT(r.time_ms, 0.0);
}

TEST(Partitioner, BadOptionsAreClearErrors) {
  const GraphStructure g = path_graph(10);
  auto message = [&](int parts, double eps) {
    try {
      run(g, parts, PartitionPreset::kFast, eps);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(0, 0.03).find("parts = 0: must be in 1..64"), std::string::npos);
  EXPECT_NE(message(65, 0.03).find("parts = 65"), std::string::npos);
  EXPECT_NE(message(2, -0.1).find("eps"), std::string::npos);
  EXPECT_NE(message(2, std::numeric_limits<double>::quiet_NaN()).find("eps"), std::string::npos);
  EXPECT_NE(message(11, 0.03).find("cannot split 10 vertices into 11"), std::string::npos);
  EXPECT_THROW(parse_preset("best"), InputError);
  EXPECT_EQ(parse_preset("highest"), PartitionPreset::kHighest);
}

}  // namespace

namespace {

using namespace tessera::partition_detail;

CycleParams relaxed_cycle(long long ub, double coarse_relax) {
  CycleParams cp = test::small_graph_cycle(ub);
  cp.coarse_relax = coarse_relax;
  return cp;
}

// The same balance bound for each of the k blocks: (1 + eps) ceil(n / k) poses.
using test::uniform_bounds;

}  // namespace

// coarse_relax loosens the bound on the coarse levels only: whatever the coarse levels did, the
// result on the input graph obeys the exact bound, and a fixed RNG seed gives the same
// partition. Without relaxation a V-cycle from a balanced partition is never worse than it
// (with it, the repair on the input graph may cost cut: the evolutionary search compares).
TEST(MultilevelCycle, RelaxedCoarseLevelsKeepTheExactBoundOnTheInputGraph) {
  const GraphStructure structure = pose_like_graph(3000, 17);
  const WorkGraph g = to_work_graph(structure);
  const int k = 5;
  const std::vector<long long> ub = uniform_bounds(structure, k, 0.03);
  for (double relax : {0.0, 0.05, 0.2}) {
    const CycleParams cp = relaxed_cycle(ub[0], relax);
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      Rng rng(seed);
      CycleStats fresh_stats;
      const std::vector<int> fresh = multilevel_partition(g, k, ub, cp, rng, &fresh_stats);
      test::expect_blocks_within(g, fresh, k, ub);
      EXPECT_GT(fresh_stats.levels, 0) << "the test graph should be coarsened";
      const long long fresh_cut = edge_cut(g, fresh);
      EXPECT_EQ(fresh_stats.cut, fresh_cut);

      const std::vector<int> cycled = guided_cycle(g, k, ub, fresh, fresh, cp, rng);
      test::expect_blocks_within(g, cycled, k, ub);
      if (relax == 0.0) {
        EXPECT_LE(edge_cut(g, cycled), fresh_cut) << "seed " << seed;
      }

      Rng again(seed);
      EXPECT_EQ(multilevel_partition(g, k, ub, cp, again), fresh);
    }
  }
}

// Even a large coarse relaxation is repaired under the tightest bound (eps = 0, every block at
// most ceil(n/k)) on the input graph, and the relaxation does change the search (otherwise the
// parameter would be ignored).
TEST(MultilevelCycle, LargeCoarseRelaxationIsRepairedUnderATightBound) {
  const GraphStructure structure = grid_graph(60, 50);
  const WorkGraph g = to_work_graph(structure);
  const int k = 7;
  const std::vector<long long> ub = uniform_bounds(structure, k, 0.0);
  int differing = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Rng r1(seed), r2(seed);
    const std::vector<int> tight = multilevel_partition(g, k, ub, relaxed_cycle(ub[0], 0.0), r1);
    const std::vector<int> relaxed = multilevel_partition(g, k, ub, relaxed_cycle(ub[0], 0.3), r2);
    test::expect_blocks_within(g, tight, k, ub);
    test::expect_blocks_within(g, relaxed, k, ub);
    differing += tight != relaxed ? 1 : 0;
  }
  EXPECT_GT(differing, 0);
}

// light_block_bounds lowers exactly one block's bound to the requested share of the average,
// raises it where the other blocks could not hold the rest, and never exceeds the input bound.
TEST(LightBlock, BoundsForceOneBlockLightAndStayFeasible) {
  const std::vector<long long> ub(5, 2100);  // rim: n = 10195, eps 0.03
  const long long total = 10195;
  const std::vector<long long> lub = light_block_bounds(ub, total, 2, 0.92);
  for (int b = 0; b < 5; ++b) {
    if (b != 2) {
      EXPECT_EQ(lub[b], 2100) << "block " << b;
    }
  }
  EXPECT_EQ(lub[2], static_cast<long long>(std::floor(0.92 * 2039.0)));  // 1875
  // 0.5 x the average would leave 10195 - 4 x 2100 = 1795 poses for block 2 plus a margin of
  // 1 % of the average (20): raised to 1815.
  EXPECT_EQ(light_block_bounds(ub, total, 2, 0.5)[2], 1815);
  // Never above the input bound.
  EXPECT_EQ(light_block_bounds(ub, total, 0, 1.2)[0], 2100);
}

// A multilevel partition and a V-cycle under light-block bounds respect them (so they respect
// the uniform bound too), the light block really is lighter than the uniform bound allows, and
// a V-cycle of that partition under the uniform bound is never worse than it.
TEST(LightBlock, MultilevelRunsRespectTheLightBound) {
  const GraphStructure structure = pose_like_graph(3000, 23);
  const WorkGraph g = to_work_graph(structure);
  const int k = 5;
  const std::vector<long long> ub = uniform_bounds(structure, k, 0.03);
  const CycleParams cp = relaxed_cycle(ub[0], 0.0);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng rng(seed);
    const std::vector<int> start = multilevel_partition(g, k, ub, cp, rng);
    const std::vector<long long> lub = random_light_bounds(g, start, ub, 0.88, 0.9, rng);
    int light = -1;
    for (int b = 0; b < k; ++b)
      if (lub[b] < ub[b]) light = b;
    ASSERT_GE(light, 0) << "one block must get a lower bound";
    EXPECT_LE(lub[light], static_cast<long long>(0.9 * 3000 / k) + 1);

    const std::vector<int> fresh = multilevel_partition(g, k, lub, cp, rng);
    test::expect_blocks_within(g, fresh, k, lub);
    const std::vector<int> pushed = guided_cycle(g, k, lub, start, start, cp, rng);
    test::expect_blocks_within(g, pushed, k, lub);
    const std::vector<int> back = guided_cycle(g, k, ub, pushed, pushed, cp, rng);
    test::expect_blocks_within(g, back, k, ub);
    EXPECT_LE(edge_cut(g, back), edge_cut(g, pushed)) << "seed " << seed;
  }
}

// The light-block tail only runs after the search stalled: with the same seed the search before
// it is identical, so the best cut with the tail is never worse than without it (and better on
// some seeds); the result respects the bound and is the same for the same seed.
TEST(LightBlock, TailAfterAStallNeverLosesTheBestCut) {
  const GraphStructure structure = pose_like_graph(3000, 17);
  const WorkGraph g = to_work_graph(structure);
  const int k = 5;
  const std::vector<long long> ub = uniform_bounds(structure, k, 0.03);
  EvolutionParams params;
  params.population = 3;
  params.generations = 40;
  params.stall_limit = 3;  // stall early so that the tail has budget left
  params.cycle = relaxed_cycle(ub[0], 0.03);
  int better = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    Rng r0(seed);
    const std::vector<int> plain = evolve(g, k, ub, params, r0, nullptr);
    EvolutionParams with_tail = params;
    with_tail.light_tail = 12;
    Rng r1(seed), r2(seed);
    const std::vector<int> tailed = evolve(g, k, ub, with_tail, r1, nullptr);
    test::expect_blocks_within(g, tailed, k, ub);
    EXPECT_LE(edge_cut(g, tailed), edge_cut(g, plain)) << "seed " << seed;
    better += edge_cut(g, tailed) < edge_cut(g, plain) ? 1 : 0;
    EXPECT_EQ(evolve(g, k, ub, with_tail, r2, nullptr), tailed);
  }
  RecordProperty("seeds_improved_by_tail", better);
  EXPECT_GT(better, 0) << "the tail never found a better cut (2 of 6 seeds did when written)";
}

// Bisection FM (k = 2) keeps each vertex's weight towards the other block up to date instead of
// rescanning its neighbours. It must make exactly the moves of the scan: the scan runs when the
// same two-block partition is refined as a 3-way one whose third block is empty and may take
// nothing (an empty block is never adjacent, so it adds no move and no random draw). Weighted
// coarse graphs (contracted) included, also coarse bounds that leave blocks above them.
TEST(KwayFm, TwoWayGainCacheMakesTheMovesOfTheScan) {
  int checked = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const WorkGraph fine =
        to_work_graph(pose_like_graph(400 + 50 * seed, static_cast<unsigned>(seed)));
    Rng crng(seed);
    CoarseningParams coarsening;
    coarsening.max_vertex_weight = 6;
    const Hierarchy h = coarsen(fine, nullptr, coarsening, crng);
    for (const WorkGraph* g : {&fine, &h.top(fine)}) {
      std::mt19937 gen(static_cast<unsigned>(seed));
      std::vector<int> start(static_cast<std::size_t>(g->n));
      for (int v = 0; v < g->n; ++v) start[v] = v < g->n / 2 + static_cast<int>(gen() % 5) ? 0 : 1;
      const long long slack = seed % 3 == 0 ? -3 : 20;  // -3: a block starts above its bound
      const long long half = g->total_vw / 2 + slack;
      FmParams fm;
      fm.max_passes = 3;
      fm.stop_after = 30;
      fm.local_rounds = seed % 2 == 0 ? 1 : 0;
      std::vector<int> two = start, three = start;
      Rng r2(seed), r3(seed);
      const long long cut2 = kway_fm(*g, 2, two, {half, half}, fm, r2);
      const long long cut3 = kway_fm(*g, 3, three, {half, half, 0}, fm, r3);
      EXPECT_EQ(two, three) << "seed " << seed << ", n " << g->n;
      EXPECT_EQ(cut2, cut3);
      EXPECT_EQ(cut2, edge_cut(*g, two));
      EXPECT_LE(cut2, edge_cut(*g, start));
      EXPECT_EQ(r2.next(), r3.next()) << "different number of random draws";
      checked += two != start;
    }
  }
  EXPECT_GT(checked, 12) << "FM moved nothing: the comparison would be empty";
}

// InitialParams::repeat_budget scales the number of recursive-bisection runs with the graph:
// clamp(round(budget / n), min_repeats, repeats) runs, the same partition as asking for that
// many runs directly. Without a budget the repeats are used as given.
TEST(InitialPartition, RepeatBudgetScalesTheRunsWithTheGraphSize) {
  const WorkGraph g = to_work_graph(pose_like_graph(800, 5));
  const int k = 9;
  const std::vector<long long> ub(k, static_cast<long long>(max_block_size(800, k, 0.03)));
  auto run = [&](int repeats, int budget, int min_repeats) {
    InitialParams ip;
    ip.repeats = repeats;
    ip.repeat_budget = budget;
    ip.min_repeats = min_repeats;
    Rng rng(3);
    std::vector<int> part = initial_partition(g, k, ub, ip, rng);
    return std::make_pair(part, rng.next());  // the next draw tells how much was drawn
  };
  const auto r1 = run(1, 0, 1), r2 = run(2, 0, 1), r3 = run(3, 0, 1), r4 = run(4, 0, 1);
  ASSERT_NE(r1.second, r2.second);
  ASSERT_NE(r2.second, r3.second);
  EXPECT_EQ(run(4, 2400, 1), r3);    // 2400 / 800 = 3 runs
  EXPECT_EQ(run(4, 1000, 1), r1);    // round(1.25) = 1
  EXPECT_EQ(run(4, 1000, 2), r2);    // raised to min_repeats
  EXPECT_EQ(run(4, 100000, 2), r4);  // capped at repeats
  EXPECT_EQ(run(3, 100000, 5), r3);  // repeats wins over a larger minimum
  test::expect_blocks_within(g, r3.first, k, ub);
}
