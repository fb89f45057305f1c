// The block re-split (block_resplit.hpp): keeping a partition's most separable blocks and
// searching the rest again finds a better arrangement of the other blocks that no local move
// reaches (horizontal strips -> vertical bands), is never worse, stays within the bounds, keeps
// the kept blocks' vertices where they were when nothing else improves, is deterministic, keeps
// a block only when asked if it is clearly separable, and runs in `highest` on small problems
// and on larger ones with a clearly separable block, not with one island. Bad options name the
// field.

#include <gtest/gtest.h>

#include <string>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/util/input_error.hpp>

#include "partition/block_resplit.hpp"
#include "partition/evolution_search.hpp"
#include "partition/evolutionary.hpp"
#include "structure_graphs.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera;
using namespace tessera::partition_detail;
using tessera::test::validation_message;
using tessera::test::validation_names;

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

// max_cut_ratio: the sub-searches run only when every kept block's cut edges are at most that
// share of the mean block cut. The strips' block 0 has 9 of a mean 34.5 (0.26): kept at 0.6,
// not at 0.2; a band layout (every block in a chain; the end blocks 0.67 of the mean at 4
// blocks) has no clearly separable block at 0.6.
TEST(BlockResplit, OnlyKeepsAClearlySeparableBlockWhenAsked) {
  const StripsCase c;
  EvolutionParams p = resplit_search(c.ub[0]);
  p.resplit.searches = 1;
  p.resplit.kept = 1;
  p.resplit.max_cut_ratio = 0.6;
  std::vector<int> part = c.strips();
  BlockResplitResult r = block_resplit(c.g, c.k, c.ub, part, p, Rng(1));
  EXPECT_TRUE(r.improved) << r.detail;
  EXPECT_EQ(edge_cut(c.g, part), 27);
  p.resplit.max_cut_ratio = 0.2;
  part = c.strips();
  r = block_resplit(c.g, c.k, c.ub, part, p, Rng(1));
  EXPECT_FALSE(r.improved);
  EXPECT_EQ(part, c.strips());
  EXPECT_EQ(r.cut, 69);
  EXPECT_NE(r.detail.find("no block clearly separable (9 cut edges, mean 35)"), std::string::npos)
      << r.detail;
  std::vector<int> bands(static_cast<std::size_t>(c.g.n));
  for (int v = 0; v < c.g.n; ++v) bands[v] = (v % 40) / 10;
  p.resplit.max_cut_ratio = 0.6;
  r = block_resplit(c.g, c.k, c.ub, bands, p, Rng(1));
  EXPECT_FALSE(r.improved);
  EXPECT_NE(r.detail.find("no block clearly separable (9 cut edges, mean 14)"), std::string::npos)
      << r.detail;
  EXPECT_TRUE(r.thread_cpu_ms.empty());
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

// The detail of the trace phase "resplit" ("" if there is none).
std::string resplit_detail(const PartitionResult& r) {
  for (const auto& t : r.trace)
    if (t.name == "resplit") return t.detail;
  return "";
}

// Whether a trace phase of that name was recorded.
bool traced(const PartitionResult& r, const std::string& phase) {
  for (const auto& t : r.trace)
    if (t.name == phase) return true;
  return false;
}

// highest re-splits small problems ((n + edges) x max(1, N/5) <= 16000) keeping 2 blocks,
// larger ones keeping 1 block only when it is clearly separable, never with --islands 1 (the
// cheapest search); strong never.
TEST(BlockResplit, HighestResplitsSmallProblemsAndClearlySeparableBlocks) {
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
  // A path of 9000 poses: 17999 > 16000. Its 5 blocks form a chain: the end blocks have 1 of
  // a mean 1.6 cut edges (0.625), none is clearly separable.
  const PartitionResult path = partition_graph(test::grid_structure(9000, 1), o);
  EXPECT_NE(resplit_detail(path).find("no block clearly separable (1 cut edges, mean 2)"),
            std::string::npos)
      << resplit_detail(path);
  EXPECT_EQ(path.metrics.cut_edges, 4u);
  // A ring of 7200 poses joined by 2 measurements each, with a path of 1800 hanging from it
  // (18000 > 16000): the best cut (9) splits the ring into 4 arcs (4 cut edges each, 5 where
  // the path hangs) and cuts the path off (1 cut edge, 0.28 of the mean block cut): that block
  // is kept and the ring searched again. (5 arcs with the path inside one would cut 10.)
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  std::vector<std::size_t> weights;
  for (std::size_t v = 0; v < 7200; ++v) {
    pairs.emplace_back(v, (v + 1) % 7200);
    weights.push_back(2);
  }
  for (std::size_t v = 7200; v < 9000; ++v) {
    pairs.emplace_back(v == 7200 ? 0 : v - 1, v);
    weights.push_back(1);
  }
  const PartitionResult ring =
      partition_graph(make_graph_structure(9000, pairs, weights, "ring"), o);
  EXPECT_EQ(ring.metrics.cut_edges, 9u);
  EXPECT_NE(resplit_detail(ring).find("keep 1: 9"), std::string::npos) << resplit_detail(ring);
}

TEST(BlockResplit, BadOptionsNameTheField) {
  BlockResplitOptions o;
  EXPECT_EQ(validation_message(o), "");
  o.searches = 9;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.searches"));
  o.searches = -1;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.searches"));
  o = {};
  o.population = 1;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.population"));
  o = {};
  o.budget = 0.0;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.budget"));
  o.budget = 1.5;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.budget"));
  o = {};
  o.kept = 0;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.kept"));
  o.kept = 63;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.kept"));
  o = {};
  o.max_parts = 1;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.max_parts"));
  o = {};
  o.max_cut_ratio = -0.1;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.max_cut_ratio"));
  o.max_cut_ratio = 1.5;
  EXPECT_TRUE(validation_names(o, "BlockResplitOptions.max_cut_ratio"));
  EvolutionParams p;
  p.resplit.budget = -1.0;
  EXPECT_TRUE(validation_names(p, "BlockResplitOptions.budget"));
}

}  // namespace
