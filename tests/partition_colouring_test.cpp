// The block adjacency (quotient) graph's colouring and the colour pass of the `rounds` objective
// (quotient_colouring.hpp): exact colour counts on layouts with a known quotient graph, fewer
// colours for a bounded cut increase with every constraint kept, block ids in colour order, the
// public option and the partitioner's time cap.

#include <gtest/gtest.h>

#include <algorithm>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/util/input_error.hpp>

#include "partition/quotient_colouring.hpp"
#include "runtime/partition_step.hpp"
#include "structure_graphs.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera;
using namespace tessera::partition_detail;
using tessera::test::validation_names;

// Block of vertex (x, y) of a w x h grid (vertex y * w + x) from a function of x and y.
template <class F>
std::vector<int> layout(int w, int h, F block) {
  std::vector<int> part(static_cast<std::size_t>(w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) part[static_cast<std::size_t>(y * w + x)] = block(x, y);
  return part;
}

// Colours a greedy colouring in block-id order uses (what the solver's block layout does).
int greedy_colours(const QuotientColouring& q) {
  std::vector<int> colour(static_cast<std::size_t>(q.k), -1);
  int used = 0;
  for (int b = 0; b < q.k; ++b) {
    int c = 0;
    for (bool clash = true; clash; ++c) {
      clash = false;
      for (int a = 0; a < b; ++a)
        clash = clash || (q.weight[static_cast<std::size_t>(b) * q.k + a] > 0 && colour[a] == c);
      if (!clash) break;
    }
    colour[b] = c;
    used = std::max(used, c + 1);
  }
  return used;
}

TEST(QuotientColouring, StripsQuadrantsAndATriangleHaveTheirChromaticNumbers) {
  const WorkGraph g = to_work_graph(test::grid_structure(12, 12));
  // Four vertical strips: a path, 3 adjacent pairs, 2 colours.
  const QuotientColouring strips =
      colour_quotient(g, layout(12, 12, [](int x, int) { return x / 3; }), 4);
  EXPECT_EQ(strips.adjacent_pairs, 3);
  EXPECT_EQ(strips.colours, 2);
  EXPECT_EQ(strips.weight[0 * 4 + 1], 12);  // one column of 12 grid edges
  // Quadrants: the diagonal ones only meet at a corner (no edge): a 4-cycle, 2 colours.
  const QuotientColouring quadrants =
      colour_quotient(g, layout(12, 12, [](int x, int y) { return (x / 6) + 2 * (y / 6); }), 4);
  EXPECT_EQ(quadrants.adjacent_pairs, 4);
  EXPECT_EQ(quadrants.colours, 2);
  // Left half, right half split top / bottom: all three pairwise adjacent, 3 colours.
  const QuotientColouring triangle = colour_quotient(
      g, layout(12, 12, [](int x, int y) { return x < 6 ? 0 : (y < 6 ? 1 : 2); }), 3);
  EXPECT_EQ(triangle.adjacent_pairs, 3);
  EXPECT_EQ(triangle.colours, 3);
  // The colouring is proper.
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      if (a != b && triangle.weight[static_cast<std::size_t>(a) * 3 + b] > 0) {
        EXPECT_NE(triangle.colour[a], triangle.colour[b]);
      }
    }
  }
}

TEST(ColourPass, MakesAllAdjacentBlocksColourableWithFewerColoursForABoundedCut) {
  const GraphStructure s = test::grid_structure(12, 12);
  const WorkGraph g = to_work_graph(s);
  const int k = 3;
  const std::vector<long long> ub = test::uniform_bounds(s, k, 0.03);
  // Balanced (48 each) and all three blocks pairwise adjacent.
  std::vector<int> part = layout(12, 12, [](int x, int y) {
    if (x < 4) return 0;
    return y < 6 ? 1 : 2;
  });
  const QuotientColouring before = colour_quotient(g, part, k);
  ASSERT_EQ(before.colours, 3);
  const long long cut_before = edge_cut(g, part);
  ColourPassOptions options;
  options.max_cut_increase = 1.0;
  Rng rng(1);
  const ColourPassResult r = colour_pass(g, k, ub, part, options, rng);
  EXPECT_EQ(r.colours_before, 3);
  EXPECT_EQ(r.colours_after, 2);
  EXPECT_EQ(r.cut_before, cut_before);
  EXPECT_EQ(r.cut_after, edge_cut(g, part));
  EXPECT_LE(r.cut_after, 2 * cut_before);
  test::expect_blocks_within(g, part, k, ub);
  const QuotientColouring after = colour_quotient(g, part, k);
  EXPECT_EQ(after.colours, 2);
  EXPECT_EQ(after.adjacent_pairs, 2);  // a path of three blocks
  EXPECT_EQ(greedy_colours(after), 2) << "blocks must be numbered in colour order";
  for (int b = 0; b < k; ++b) EXPECT_GT(std::count(part.begin(), part.end(), b), 0);
}

TEST(ColourPass, KeepsThePartitionWhenTheCutMayNotGrow) {
  const GraphStructure s = test::grid_structure(12, 12);
  const WorkGraph g = to_work_graph(s);
  const std::vector<long long> ub = test::uniform_bounds(s, 3, 0.03);
  const std::vector<int> start = layout(12, 12, [](int x, int y) {
    if (x < 4) return 0;
    return y < 6 ? 1 : 2;
  });
  std::vector<int> part = start;
  ColourPassOptions options;
  options.max_cut_increase = 0.0;
  Rng rng(1);
  const ColourPassResult r = colour_pass(g, 3, ub, part, options, rng);
  EXPECT_EQ(r.colours_after, 3);
  EXPECT_EQ(r.cut_after, r.cut_before);
  EXPECT_EQ(part, start);  // already in colour order
}

TEST(ColourPass, ForbiddenPairsHoldThroughFmAndRebalance) {
  // Three vertical strips, blocks 0 | 1 | 2, with 0 and 2 forbidden to touch; block 1 is over
  // its bound, so rebalance has to move two of its vertices out and FM then refines: no move may
  // join 0 and 2.
  const GraphStructure s = test::grid_structure(9, 9);
  const WorkGraph g = to_work_graph(s);
  const int k = 3;
  std::vector<int> part = layout(9, 9, [](int x, int) { return x < 3 ? 0 : (x < 6 ? 1 : 2); });
  ForbiddenPairs forbidden(9, 0);
  forbidden[0 * 3 + 2] = forbidden[2 * 3 + 0] = 1;
  const std::vector<long long> tight = {28, 25, 28};  // block 1 (27 vertices) is over
  ASSERT_TRUE(rebalance(g, k, part, tight, &forbidden));
  Rng rng(3);
  FmParams fm;
  fm.max_passes = 4;
  kway_fm(g, k, part, tight, fm, rng, -1, &forbidden);
  const QuotientColouring q = colour_quotient(g, part, k);
  EXPECT_EQ(q.weight[0 * 3 + 2], 0);
  test::expect_blocks_within(g, part, k, tight);
}

TEST(PartitionObjective, RoundsGivesNoMoreColoursForABoundedCutAndIsDeterministic) {
  const GraphStructure s = test::grid_with_chords(30, 30, 5);
  for (int k : {4, 5, 6}) {
    PartitionOptions cut;
    cut.parts = k;
    cut.preset = PartitionPreset::kEco;
    PartitionOptions rounds = cut;
    rounds.objective = PartitionObjective::kRounds;
    const PartitionResult a = partition_graph(s, cut);
    const PartitionResult b = partition_graph(s, rounds);
    const PartitionResult c = partition_graph(s, rounds);
    EXPECT_LE(b.colours, a.colours) << "k = " << k;
    EXPECT_LE(static_cast<double>(b.metrics.cut_edges),
              1.25 * static_cast<double>(a.metrics.cut_edges) + 1e-9);
    EXPECT_LE(b.metrics.max_block, b.max_block_size);
    EXPECT_EQ(b.assignment, c.assignment);
    const WorkGraph g = to_work_graph(s);
    EXPECT_EQ(colour_quotient(g, b.assignment, k).colours, b.colours);
  }
}

TEST(PartitionObjective, TheCoordinatorPartitionsForRounds) {
  const GraphStructure s = test::grid_with_chords(20, 20, 3);
  PartitionOptions o;
  o.parts = 5;
  o.preset = PartitionPreset::kEco;
  o.seed = 4;
  o.objective = PartitionObjective::kRounds;
  const PartitionResult r = partition_graph(s, o);
  const coordinator::PartitionStepResult step = coordinator::partition_for_agents(s, 5, "eco", 4);
  ASSERT_EQ(step.owner.size(), r.assignment.size());
  for (std::size_t v = 0; v < step.owner.size(); ++v)
    ASSERT_EQ(static_cast<int>(step.owner[v]), r.assignment[v]) << "pose " << v;
  EXPECT_EQ(step.cut_edges, r.metrics.cut_edges);
}

// solve's and launch's default: fast on a small graph, eco on a large one, the same partition as
// naming that preset.
TEST(PartitionObjective, TheAutoPresetIsFastOnSmallGraphsAndEcoOnLargeOnes) {
  EXPECT_EQ(auto_preset(kAutoPresetFastBelow - 1), PartitionPreset::kFast);
  EXPECT_EQ(auto_preset(kAutoPresetFastBelow), PartitionPreset::kEco);
  EXPECT_EQ(parse_preset_for("auto", 10), PartitionPreset::kFast);
  EXPECT_EQ(parse_preset_for("highest", 10), PartitionPreset::kHighest);
  EXPECT_THROW(parse_preset("auto"), InputError);  // tessera partition names its effort
  for (int side : {20, 50}) {                      // 400 and 2500 poses
    const GraphStructure s = test::grid_with_chords(side, side, 3);
    const char* named = s.num_vertices < kAutoPresetFastBelow ? "fast" : "eco";
    const coordinator::PartitionStepResult a = coordinator::partition_for_agents(s, 5, "auto", 2);
    const coordinator::PartitionStepResult b = coordinator::partition_for_agents(s, 5, named, 2);
    EXPECT_EQ(a.owner, b.owner) << named;
  }
}

TEST(PartitionObjective, NamesAndValidation) {
  EXPECT_EQ(parse_objective("cut"), PartitionObjective::kCut);
  EXPECT_EQ(parse_objective("rounds"), PartitionObjective::kRounds);
  EXPECT_STREQ(objective_name(PartitionObjective::kRounds), "rounds");
  EXPECT_THROW(parse_objective("colours"), InputError);
  PartitionOptions o;
  o.colour_cut_slack = -0.1;
  EXPECT_TRUE(validation_names(o, "colour_cut_slack"));
  o = PartitionOptions{};
  o.time_limit_s = -1;
  EXPECT_TRUE(validation_names(o, "time_limit_s"));
  o = PartitionOptions{};
  o.stall_steps = -1;
  EXPECT_TRUE(validation_names(o, "stall_steps"));
}

TEST(PartitionTimeCap, EndsTheSearchEarlyAndStillGivesAValidPartition) {
  const GraphStructure s = test::grid_with_chords(24, 24, 2);
  PartitionOptions o;
  o.parts = 5;
  o.preset = PartitionPreset::kHighest;
  o.islands = 1;
  o.time_limit_s = 1e-6;  // passed before the first step: one multilevel run, nothing after
  const PartitionResult r = partition_graph(s, o);
  EXPECT_LE(r.metrics.max_block, r.max_block_size);
  for (const auto& p : r.trace) {
    EXPECT_NE(p.name, "polish");
    EXPECT_NE(p.name, "resplit");
  }
  // A stall window of one step: the search ends at its first step without a better cut, and
  // the result is as valid.
  PartitionOptions w;
  w.parts = 5;
  w.preset = PartitionPreset::kStrong;
  w.stall_steps = 1;
  const PartitionResult rw = partition_graph(s, w);
  EXPECT_LE(rw.metrics.max_block, rw.max_block_size);
}

}  // namespace
