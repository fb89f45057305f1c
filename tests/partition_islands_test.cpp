// The island model of the memetic search (island_search.hpp): two islands on their own threads
// give the same partition for the same seed (with and without exchanges, through evolve() and
// through the `highest` preset), two islands that never exchange are never worse than the single
// search (island 0 is that search step for step), a short island is the start of the full one,
// `highest` runs two islands and a short one unless asked otherwise, and bad options name the
// field.

#include <gtest/gtest.h>

#include <string>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/util/input_error.hpp>

#include "partition/evolutionary.hpp"
#include "partition/island_search.hpp"
#include "structure_graphs.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera;
using namespace tessera::partition_detail;
using tessera::test::validation_message;
using tessera::test::validation_names;

using test::grid_with_chords;

using test::small_search;

TEST(IslandSearch, SameSeedSamePartitionWithThreads) {
  const GraphStructure structure = grid_with_chords(30, 20, 3);
  const WorkGraph g = to_work_graph(structure);
  const int k = 5;
  const std::vector<long long> ub = test::uniform_bounds(structure, k, 0.03);
  for (int exchange : {0, 3}) {
    EvolutionParams p = small_search(ub[0]);
    p.islands.islands = 2;
    p.islands.exchange_every = exchange;
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      Rng r1(seed), r2(seed);
      const std::vector<int> a = evolve(g, k, ub, p, r1, nullptr);
      const std::vector<int> b = evolve(g, k, ub, p, r2, nullptr);
      test::expect_blocks_within(g, a, k, ub);
      EXPECT_EQ(a, b) << "exchange " << exchange << " seed " << seed;
      EXPECT_EQ(r1.next(), r2.next()) << "the caller's generator must end in the same state";
    }
  }
}

// The comparisons of one search against islands: a 30 x 20 grid with chords, 5 blocks.
struct IslandCase {
  GraphStructure structure = grid_with_chords(30, 20, 5);
  WorkGraph g = to_work_graph(structure);
  int k = 5;
  std::vector<long long> ub = test::uniform_bounds(structure, k, 0.03);
  EvolutionParams one = small_search(ub[0]);
  EvolutionParams two() const {
    EvolutionParams p = one;
    p.islands.islands = 2;
    return p;
  }
};

// Island 0 draws the single search's random stream, so without exchanges the best of two islands
// can only be at least as good as the single search; on some seeds island 1 is better.
TEST(IslandSearch, TwoIslandsWithoutExchangeNeverLoseToOne) {
  const IslandCase c;
  int better = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    Rng r1(seed), r2(seed);
    const long long single = edge_cut(c.g, evolve(c.g, c.k, c.ub, c.one, r1, nullptr));
    const long long islands = edge_cut(c.g, evolve(c.g, c.k, c.ub, c.two(), r2, nullptr));
    EXPECT_LE(islands, single) << "seed " << seed;
    better += islands < single ? 1 : 0;
  }
  RecordProperty("seeds_improved_by_second_island", better);
}

// IslandOptions::second_matching_share changes island 1's coarsening only: island 0 is still the
// single search (never worse than it), a share equal to EvolutionParams::matching_share gives
// exactly the default two islands, and the result is deterministic.
TEST(IslandSearch, SecondIslandOwnMatchingShareLeavesIslandZero) {
  const IslandCase c;
  EvolutionParams same = c.two();
  same.islands.second_matching_share = c.one.matching_share;
  EvolutionParams other = c.two();
  other.islands.second_matching_share = 1.0;
  int differs = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    Rng r1(seed), r2(seed), r3(seed), r4(seed), r5(seed);
    const long long single = edge_cut(c.g, evolve(c.g, c.k, c.ub, c.one, r1, nullptr));
    const std::vector<int> plain = evolve(c.g, c.k, c.ub, c.two(), r2, nullptr);
    EXPECT_EQ(evolve(c.g, c.k, c.ub, same, r3, nullptr), plain) << "seed " << seed;
    const std::vector<int> a = evolve(c.g, c.k, c.ub, other, r4, nullptr);
    EXPECT_EQ(evolve(c.g, c.k, c.ub, other, r5, nullptr), a) << "seed " << seed;
    test::expect_blocks_within(c.g, a, c.k, c.ub);
    EXPECT_LE(edge_cut(c.g, a), single) << "seed " << seed;
    differs += a != plain ? 1 : 0;
  }
  EXPECT_GT(differs, 0) << "island 1 with matching coarsening must search differently";
}

// A short island is the first steps of the full island with the same index: with the whole
// budget it is exactly a third full island, with a quarter it runs at most a quarter of the
// steps, islands 0 and 1 are unchanged (never worse than two islands), and the result does not
// depend on which thread ran it (same partition twice).
TEST(IslandSearch, ShortIslandIsTheStartOfTheFullOne) {
  const IslandCase c;
  EvolutionParams three = c.two();
  three.islands.islands = 3;
  EvolutionParams whole = c.two();
  whole.islands.short_islands = 1;
  whole.islands.short_budget = 1.0;
  EvolutionParams quarter = c.two();
  quarter.islands.short_islands = 1;
  quarter.islands.short_budget = 0.25;
  int differs = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    Rng r1(seed), r2(seed), r3(seed), r4(seed), r5(seed);
    const std::vector<int> full = evolve(c.g, c.k, c.ub, three, r1, nullptr);
    EXPECT_EQ(evolve(c.g, c.k, c.ub, whole, r2, nullptr), full) << "seed " << seed;
    const long long two = edge_cut(c.g, evolve(c.g, c.k, c.ub, c.two(), r3, nullptr));
    std::string detail;
    const std::vector<int> a = evolve(
        c.g, c.k, c.ub, quarter, r4, [&](const std::string& name, const std::string& d, long long) {
          if (name == "evolution") detail = d;
        });
    EXPECT_EQ(evolve(c.g, c.k, c.ub, quarter, r5, nullptr), a) << "seed " << seed;
    test::expect_blocks_within(c.g, a, c.k, c.ub);
    EXPECT_LE(edge_cut(c.g, a), two) << "seed " << seed;
    // small_search has 12 steps: the short island gets 3.
    EXPECT_NE(detail.find("island 2: short, 3 combine/mutation steps"), std::string::npos)
        << detail;
    differs += edge_cut(c.g, a) < two ? 1 : 0;
  }
  RecordProperty("seeds_improved_by_short_island", differs);
}

// Whether the `evolution` trace phase names island `i` (followed by `kind`, e.g. "short").
bool traces_island(const PartitionResult& r, int i, const std::string& kind = "") {
  const std::string name = "island " + std::to_string(i) + ":" + (kind.empty() ? "" : " " + kind);
  for (const auto& t : r.trace)
    if (t.name == "evolution" && t.detail.find(name) != std::string::npos) return true;
  return false;
}

TEST(IslandSearch, HighestPresetIsDeterministicAndTracesTheIslands) {
  const GraphStructure structure = grid_with_chords(24, 16, 7);
  PartitionOptions o;
  o.parts = 5;
  o.preset = PartitionPreset::kHighest;
  o.seed = 9;
  const PartitionResult a = partition_graph(structure, o);
  const PartitionResult b = partition_graph(structure, o);
  EXPECT_EQ(a.assignment, b.assignment);
  EXPECT_TRUE(traces_island(a, 1)) << "highest must run several islands";
}

// highest runs two islands and a short one unless PartitionOptions::islands asks for more (four:
// islands 0-3 traced, then the short island 4, no sixth) or its step budget is small. The
// path's optimal cuts (9, 19) are found either way.
TEST(IslandSearch, HighestRunsTwoIslandsUnlessAskedForFour) {
  PartitionOptions o;
  o.preset = PartitionPreset::kHighest;
  o.parts = 5;
  o.seed = 2;
  const PartitionResult two = partition_graph(grid_with_chords(24, 16, 7), o);
  EXPECT_TRUE(traces_island(two, 1));
  EXPECT_TRUE(traces_island(two, 2, "short"));
  EXPECT_FALSE(traces_island(two, 3));
  o.islands = 4;
  const PartitionResult four = partition_graph(grid_with_chords(24, 16, 7), o);
  EXPECT_TRUE(traces_island(four, 3));
  EXPECT_FALSE(traces_island(four, 3, "short"));
  EXPECT_TRUE(traces_island(four, 4, "short"));
  EXPECT_FALSE(traces_island(four, 5));
  o.islands = 0;
  o.parts = 10;
  const PartitionResult path = partition_graph(test::grid_structure(8000, 1), o);
  EXPECT_TRUE(traces_island(path, 1));
  EXPECT_FALSE(traces_island(path, 3));
  EXPECT_EQ(path.metrics.cut_edges, 9u);
  EXPECT_LE(path.metrics.max_block_ratio, 1.03 + 1e-12);
  // 20 blocks of the path leave 27 steps: a fifth (5) is fewer than the population (8), so
  // there is no short island (it would be mostly a population build).
  o.parts = 20;
  const PartitionResult many = partition_graph(test::grid_structure(8000, 1), o);
  EXPECT_TRUE(traces_island(many, 1));
  EXPECT_FALSE(traces_island(many, 2));
  EXPECT_EQ(many.metrics.cut_edges, 19u);
}

// PartitionOptions::islands overrides the preset's count (one island: the single search, no
// island in the trace); out of range it is refused naming the field.
TEST(IslandSearch, PartitionOptionsChooseTheIslandCount) {
  const GraphStructure structure = grid_with_chords(24, 16, 7);
  PartitionOptions o;
  o.parts = 4;
  o.preset = PartitionPreset::kHighest;
  o.seed = 3;
  o.islands = 1;
  const PartitionResult one = partition_graph(structure, o);
  for (const auto& t : one.trace)
    EXPECT_EQ(t.detail.find("island"), std::string::npos) << t.name << ": " << t.detail;
  o.islands = 9;
  EXPECT_NE(tessera::test::input_error_of([&] {
              partition_graph(structure, o);
            }).find("PartitionOptions.islands"),
            std::string::npos);
}

TEST(IslandSearch, BadOptionsNameTheField) {
  EvolutionParams p;
  EXPECT_EQ(validation_message(p), "");
  p.islands.islands = 0;
  EXPECT_TRUE(validation_names(p, "IslandOptions.islands"));
  p.islands.islands = 9;
  EXPECT_TRUE(validation_names(p, "IslandOptions.islands"));
  p = {};
  p.islands.exchange_every = -1;
  EXPECT_TRUE(validation_names(p, "IslandOptions.exchange_every"));
  p = {};
  p.islands.second_matching_share = 1.5;
  EXPECT_TRUE(validation_names(p, "IslandOptions.second_matching_share"));
  p.islands.second_matching_share = -0.5;
  EXPECT_TRUE(validation_names(p, "IslandOptions.second_matching_share"));
  p = {};
  p.islands.short_islands = 9;
  EXPECT_TRUE(validation_names(p, "IslandOptions.short_islands"));
  p = {};
  p.islands.short_budget = 0.0;
  EXPECT_TRUE(validation_names(p, "IslandOptions.short_budget"));
  p.islands.short_budget = 1.5;
  EXPECT_TRUE(validation_names(p, "IslandOptions.short_budget"));
  p = {};
  p.islands.islands = 8;
  p.islands.exchange_every = 5;
  EXPECT_EQ(validation_message(p), "");
}

}  // namespace
