// The block re-split (block_resplit.hpp): keeping a partition's most separable blocks and
// searching the rest again finds a better arrangement of the other blocks that no local move
// reaches (horizontal strips -> vertical bands), is never worse, stays within the bounds, keeps
// the kept blocks' vertices where they were when nothing else improves, is deterministic, and
// runs in `highest` only on small problems and not with one island. Bad options name the field.

#include <gtest/gtest.h>

#include <string>

#include "partition/block_resplit.hpp"
#include "partition/evolution_search.hpp"
#include "partition/evolutionary.hpp"
#include "partition/graph_structure.hpp"
#include "partition/partitioner.hpp"
#include "structure_graphs.hpp"
#include "test_support.hpp"
#include "util/input_error.hpp"

namespace {

using namespace tessera;
using namespace tessera::partition_detail;
using tessera::test::validation_message;

// test::small_search with small re-split sub-searches (population 3, its 12 steps).
EvolutionParams resplit_search(long long bound) {
  EvolutionParams p = test::small_search(bound);
  p.resplit.population = 3;
  p.resplit.budget = 1.0;
  return p;
}

// A 30 x 20 grid with chords in 5 blocks.
struct ChordsCase {
  GraphStructure structure = test::grid_with_chords(30, 20, 5);
  WorkGraph g = to_work_graph(structure);
  int k = 5;
  std::vector<long long> ub = test::uniform_bounds(structure, k, 0.03);
};

// A 40 x 9 grid in 4 blocks of 90 (bound 92): columns 0-9 are block 0 (9 cut edges, the most
// separable block), the other 30 columns are cut into three horizontal strips of 3 rows (cut
// 9 + 2 x 30 = 69). The optimum is 4 vertical bands (27). Turning the strips into bands moves
// two thirds of their vertices at once; keeping block 0 and splitting the rest again does it.
struct StripsCase {
  GraphStructure structure = test::grid_structure(40, 9);
  WorkGraph g = to_work_graph(structure);
  int k = 4;
  std::vector<long long> ub = test::uniform_bounds(structure, k, 0.03);
  std::vector<int> strips() const {
    std::vector<int> part(static_cast<std::size_t>(g.n));
    for (int v = 0; v < g.n; ++v) {
      const int x = v % 40, y = v / 40;
      part[v] = x < 10 ? 0 : 1 + y / 3;
    }
    return part;
  }
};

TEST(BlockResplit, TurnsStripsIntoBandsKeepingTheSeparableBlock) {
  const StripsCase c;
  ASSERT_EQ(c.ub[0], 92);
  ASSERT_EQ(edge_cut(c.g, c.strips()), 69);
  EvolutionParams p = resplit_search(c.ub[0]);
  p.resplit.searches = 1;
  p.resplit.kept = 1;  // block 0 (9 cut edges)
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    // A V-cycle of the whole partition (FM and flows on every level) does not get there.
    Rng vrng(seed);
    const Individual cycled = vcycle(c.g, c.k, c.ub, {c.strips(), 69}, p.cycle, vrng);
    EXPECT_GT(cycled.cut, 27) << "seed " << seed;
    std::vector<int> part = c.strips();
    const BlockResplitResult r = block_resplit(c.g, c.k, c.ub, part, p, Rng(seed));
    EXPECT_TRUE(r.improved) << "seed " << seed;
    test::expect_blocks_within(c.g, part, c.k, c.ub);
    EXPECT_EQ(edge_cut(c.g, part), 27) << "seed " << seed << ": " << r.detail;
    EXPECT_NE(r.detail.find("keep 1: 27"), std::string::npos) << r.detail;
  }
}

TEST(BlockResplit, NeverWorseWithinBoundsAndDeterministic) {
  const ChordsCase c;
  const WorkGraph& g = c.g;
  const int k = c.k;
  const std::vector<long long>& ub = c.ub;
  EvolutionParams p = resplit_search(ub[0]);
  p.resplit.searches = 2;
  int improved = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    EvolutionParams plain = p;
    plain.resplit.searches = 0;
    Rng r0(seed);
    const std::vector<int> start = evolve(g, k, ub, plain, r0, nullptr);
    std::vector<int> a = start, b = start;
    const Rng rng(seed + 100);
    const BlockResplitResult ra = block_resplit(g, k, ub, a, p, rng);
    const BlockResplitResult rb = block_resplit(g, k, ub, b, p, rng);
    EXPECT_EQ(a, b) << "seed " << seed;
    EXPECT_EQ(ra.detail.substr(0, ra.detail.find(", thread")),
              rb.detail.substr(0, rb.detail.find(", thread")));
    test::expect_blocks_within(g, a, k, ub);
    if (ra.improved)
      EXPECT_LT(edge_cut(g, a), edge_cut(g, start)) << "seed " << seed;
    else
      EXPECT_EQ(a, start) << "seed " << seed;
    improved += ra.improved ? 1 : 0;
  }
  RecordProperty("seeds_improved_by_resplit", improved);
}

// Through evolve(): the result is never worse than the search without the re-split (it runs
// last and only replaces a strictly better partition), and the trace names it.
TEST(BlockResplit, AfterTheSearchNeverWorseAndTraced) {
  const ChordsCase c;
  const WorkGraph& g = c.g;
  const int k = c.k;
  const std::vector<long long>& ub = c.ub;
  EvolutionParams with = resplit_search(ub[0]);
  with.resplit.searches = 2;
  EvolutionParams without = with;
  without.resplit.searches = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng r1(seed), r2(seed);
    std::string detail;
    const std::vector<int> a =
        evolve(g, k, ub, with, r1, [&](const std::string& name, const std::string& d, long long) {
          if (name == "resplit") detail = d;
        });
    const std::vector<int> b = evolve(g, k, ub, without, r2, nullptr);
    EXPECT_LE(edge_cut(g, a), edge_cut(g, b)) << "seed " << seed;
    if (edge_cut(g, a) == edge_cut(g, b)) {
      EXPECT_EQ(a, b) << "seed " << seed;
    }
    // Two sub-searches, each keeping the 2 most separable blocks.
    const std::size_t first = detail.find("keep 2: ");
    ASSERT_NE(first, std::string::npos) << detail;
    EXPECT_NE(detail.find("keep 2: ", first + 1), std::string::npos) << detail;
  }
}

TEST(BlockResplit, OffOrTooManyBlocksLeavesThePartition) {
  const StripsCase c;
  EvolutionParams p = resplit_search(c.ub[0]);
  std::vector<int> part = c.strips();
  EXPECT_FALSE(block_resplit(c.g, c.k, c.ub, part, p, Rng(1)).improved);  // searches = 0
  p.resplit.searches = 2;
  p.resplit.max_parts = 3;
  EXPECT_FALSE(block_resplit(c.g, c.k, c.ub, part, p, Rng(1)).improved);
  EXPECT_EQ(part, c.strips());
  // Two blocks: nothing to keep while splitting two again.
  const std::vector<long long> two = test::uniform_bounds(c.structure, 2, 0.03);
  std::vector<int> halves(static_cast<std::size_t>(c.g.n));
  for (int v = 0; v < c.g.n; ++v) halves[v] = v % 40 < 20 ? 0 : 1;
  p.resplit.max_parts = 8;
  const std::vector<int> before = halves;
  EXPECT_FALSE(block_resplit(c.g, 2, two, halves, p, Rng(1)).improved);
  EXPECT_EQ(halves, before);
}

// Whether a trace phase of that name was recorded.
bool traced(const PartitionResult& r, const std::string& phase) {
  for (const auto& t : r.trace)
    if (t.name == phase) return true;
  return false;
}

// highest re-splits on small problems ((n + edges) x max(1, N/5) <= 16000), never with
// --islands 1 (the cheapest search) and not on larger ones; strong never.
TEST(BlockResplit, HighestResplitsSmallProblemsOnly) {
  PartitionOptions o;
  o.preset = PartitionPreset::kHighest;
  o.parts = 5;
  const GraphStructure small = test::grid_with_chords(24, 16, 7);
  EXPECT_TRUE(traced(partition_graph(small, o), "resplit"));
  o.islands = 1;
  EXPECT_FALSE(traced(partition_graph(small, o), "resplit"));
  o.islands = 0;
  o.preset = PartitionPreset::kStrong;
  EXPECT_FALSE(traced(partition_graph(small, o), "resplit"));
  o.preset = PartitionPreset::kHighest;
  // A path of 9000 poses: 17999 > 16000.
  const PartitionResult large = partition_graph(test::grid_structure(9000, 1), o);
  EXPECT_FALSE(traced(large, "resplit"));
  EXPECT_EQ(large.metrics.cut_edges, 4u);
}

TEST(BlockResplit, BadOptionsNameTheField) {
  BlockResplitOptions o;
  EXPECT_EQ(validation_message(o), "");
  auto names = [](BlockResplitOptions bad, const std::string& field) {
    return validation_message(bad).find("BlockResplitOptions." + field) != std::string::npos;
  };
  o.searches = 9;
  EXPECT_TRUE(names(o, "searches"));
  o.searches = -1;
  EXPECT_TRUE(names(o, "searches"));
  o = {};
  o.population = 1;
  EXPECT_TRUE(names(o, "population"));
  o = {};
  o.budget = 0.0;
  EXPECT_TRUE(names(o, "budget"));
  o.budget = 1.5;
  EXPECT_TRUE(names(o, "budget"));
  o = {};
  o.kept = 0;
  EXPECT_TRUE(names(o, "kept"));
  o.kept = 63;
  EXPECT_TRUE(names(o, "kept"));
  o = {};
  o.max_parts = 1;
  EXPECT_TRUE(names(o, "max_parts"));
  EvolutionParams p;
  p.resplit.budget = -1.0;
  EXPECT_NE(validation_message(p).find("BlockResplitOptions.budget"), std::string::npos);
}

}  // namespace
