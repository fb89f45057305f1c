// Relax / repair refinement of a finished partition (relaxed_polish.hpp) and its place after the
// memetic search: a chain of moves that no move under the exact bound can start is found, the cut
// never gets worse, the bound holds, the result is deterministic, and bad options name the field.

#include <gtest/gtest.h>

#include <tessera/partition/graph_structure.hpp>
#include <tessera/util/input_error.hpp>

#include "partition/evolutionary.hpp"
#include "partition/relaxed_polish.hpp"
#include "structure_graphs.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera;
using namespace tessera::partition_detail;
using tessera::test::validation_message;
using tessera::test::validation_names;

// A 10 x 10 grid in two halves of exactly 50 vertices (bound 50, no slack), except that one
// vertex of each half sits on the other side: cut 14 instead of the straight 10. Each tooth
// moves home with gain 2, but only after the other one: a single move overfills a block, so FM
// under the bound cannot start, and flow corridors are empty without slack. One relaxed round
// moves both.
TEST(RelaxedPolish, MovesAChainThatNoBoundedMoveCanStart) {
  const WorkGraph g = to_work_graph(test::grid_structure(10, 10));
  const int k = 2;
  const std::vector<long long> ub(2, 50);
  std::vector<int> part(100);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 10; ++x) part[y * 10 + x] = x < 5 ? 0 : 1;
  part[2 * 10 + 5] = 0;
  part[7 * 10 + 4] = 1;
  ASSERT_EQ(edge_cut(g, part), 14);
  const CycleParams cycle = test::small_graph_cycle(50);

  std::vector<int> fm_only = part;
  Rng r0(1);
  EXPECT_EQ(kway_fm(g, k, fm_only, ub, cycle.fm, r0), 14) << "FM alone must be stuck here";

  RelaxedPolishOptions options;
  options.rounds = 1;
  std::vector<int> polished = part;
  Rng r1(1);
  EXPECT_EQ(relaxed_polish(g, k, ub, polished, options, cycle, r1), 10);
  EXPECT_EQ(edge_cut(g, polished), 10);
  test::expect_blocks_within(g, polished, k, ub);

  options.rounds = 0;  // off: unchanged
  std::vector<int> off = part;
  Rng r2(1);
  EXPECT_EQ(relaxed_polish(g, k, ub, off, options, cycle, r2), 14);
  EXPECT_EQ(off, part);
}

// On irregular graphs with a few blocks at the bound: never worse than its start, within the
// bound, and the same for the same seed; better than the start on some seeds.
TEST(RelaxedPolish, NeverWorseWithinTheBoundAndDeterministic) {
  int better = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    // A 40 x 30 grid plus 300 random short-range chords (loop closures).
    const GraphStructure structure = test::grid_with_chords(40, 30, seed);
    const WorkGraph g = to_work_graph(structure);
    const int k = 5;
    const std::vector<long long> ub = test::uniform_bounds(structure, k, 0.03);
    CycleParams cycle = test::small_graph_cycle(ub[0]);
    cycle.use_flow = true;
    Rng rng(seed);
    const std::vector<int> start = multilevel_partition(g, k, ub, cycle, rng);
    const long long start_cut = edge_cut(g, start);
    RelaxedPolishOptions options;
    options.rounds = 4;
    std::vector<int> a = start, b = start;
    Rng ra(seed), rb(seed);
    const long long cut = relaxed_polish(g, k, ub, a, options, cycle, ra);
    EXPECT_EQ(cut, edge_cut(g, a));
    EXPECT_LE(cut, start_cut) << "seed " << seed;
    test::expect_blocks_within(g, a, k, ub);
    relaxed_polish(g, k, ub, b, options, cycle, rb);
    EXPECT_EQ(a, b) << "seed " << seed;
    better += cut < start_cut ? 1 : 0;
  }
  RecordProperty("seeds_improved", better);
  EXPECT_GT(better, 0) << "the polish never improved a fresh multilevel partition";
}

// After the memetic search: the search runs exactly as without the polish (its own generator),
// so the result is never worse than without it, and it is deterministic.
TEST(RelaxedPolish, AfterTheSearchItNeverLosesTheBestCut) {
  const GraphStructure structure = test::grid_structure(60, 25);
  const WorkGraph g = to_work_graph(structure);
  const int k = 5;
  const std::vector<long long> ub = test::uniform_bounds(structure, k, 0.03);
  EvolutionParams params;
  params.population = 3;
  params.generations = 6;
  params.cycle = test::small_graph_cycle(ub[0]);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng r0(seed);
    const std::vector<int> plain = evolve(g, k, ub, params, r0, nullptr);
    EvolutionParams with = params;
    with.polish.rounds = 3;
    Rng r1(seed), r2(seed);
    const std::vector<int> polished = evolve(g, k, ub, with, r1, nullptr);
    test::expect_blocks_within(g, polished, k, ub);
    EXPECT_LE(edge_cut(g, polished), edge_cut(g, plain)) << "seed " << seed;
    EXPECT_EQ(evolve(g, k, ub, with, r2, nullptr), polished);
  }
}

TEST(RelaxedPolish, BadOptionsNameTheField) {
  RelaxedPolishOptions o;
  o.rounds = -1;
  EXPECT_TRUE(validation_names(o, "RelaxedPolishOptions.rounds"));
  o = {};
  o.min_relax = 0.0;
  EXPECT_TRUE(validation_names(o, "RelaxedPolishOptions.min_relax"));
  o = {};
  o.max_relax = 0.001;  // below min_relax
  EXPECT_TRUE(validation_names(o, "RelaxedPolishOptions.max_relax"));
  EXPECT_EQ(validation_message(RelaxedPolishOptions{}), "");
}

TEST(EvolutionParams, BadOptionsNameTheField) {
  EvolutionParams p;
  EXPECT_EQ(validation_message(p), "");
  p.population = 0;
  EXPECT_TRUE(validation_names(p, "EvolutionParams.population"));
  p = {};
  p.mutation_rate = 1.5;
  EXPECT_TRUE(validation_names(p, "EvolutionParams.mutation_rate"));
  p = {};
  p.polish.max_relax = 0.9;
  EXPECT_TRUE(validation_names(p, "RelaxedPolishOptions.max_relax"));
}

}  // namespace
