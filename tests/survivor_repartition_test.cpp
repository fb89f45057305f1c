// Re-partition after agents are lost for good: every pose ends up with a survivor, survivors
// keep their own poses (grow), balance holds over the survivors, results are deterministic,
// and the replica plan picks the right holders.

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <tessera/distributed/replica_plan.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/partition/survivor_repartition.hpp>
#include <tessera/util/input_error.hpp>

#include "random_graph.hpp"

namespace tessera {
namespace {

GraphStructure path(std::size_t n) {
  std::vector<std::pair<std::size_t, std::size_t>> e;
  for (std::size_t v = 0; v + 1 < n; ++v) e.emplace_back(v, v + 1);
  return make_graph_structure(n, e, "path");
}

GraphStructure random_structure(std::size_t poses, std::uint64_t seed) {
  test::RandomGraphSpec spec;
  spec.poses = poses;
  spec.loop_closures = poses / 2;
  spec.seed = seed;
  return graph_structure_from_pose_graph(test::random_pose_graph(spec));
}

std::vector<int> partition(const GraphStructure& g, int parts) {
  PartitionOptions o;
  o.parts = parts;
  o.preset = PartitionPreset::kEco;
  return partition_graph(g, o).assignment;
}

void expect_valid(const GraphStructure& g, const std::vector<int>& old_owner, int N,
                  const std::vector<int>& lost, const SurvivorRepartitionResult& r) {
  const std::set<int> gone(lost.begin(), lost.end());
  ASSERT_EQ(r.survivors.size(), static_cast<std::size_t>(N) - gone.size());
  ASSERT_EQ(r.owner.size(), g.num_vertices);
  ASSERT_EQ(r.block.size(), g.num_vertices);
  std::size_t lost_poses = 0, moved = 0;
  for (std::size_t v = 0; v < g.num_vertices; ++v) {
    EXPECT_EQ(gone.count(r.owner[v]), 0u) << "pose " << v << " left with a lost agent";
    ASSERT_GE(r.block[v], 0);
    ASSERT_LT(r.block[v], static_cast<int>(r.survivors.size()));
    EXPECT_EQ(r.survivors[static_cast<std::size_t>(r.block[v])], r.owner[v]);
    lost_poses += gone.count(old_owner[v]);
    moved += r.owner[v] != old_owner[v];
  }
  EXPECT_EQ(r.lost_poses, lost_poses);
  EXPECT_EQ(r.moved_poses, moved);
  EXPECT_LE(r.metrics.max_block, r.max_block_size);
  EXPECT_EQ(r.max_block_size,
            max_block_size(g.num_vertices, static_cast<int>(r.survivors.size()), 0.03));
}

TEST(SurvivorRepartition, PathMiddleBlockSplitsIntoItsNeighboursWithOneCut) {
  const GraphStructure g = path(10);
  const std::vector<int> owner = {0, 0, 0, 0, 1, 1, 1, 2, 2, 2};
  const auto r = repartition_for_survivors(g, owner, 3, {1});
  expect_valid(g, owner, 3, {1}, r);
  EXPECT_EQ(r.survivors, (std::vector<int>{0, 2}));
  EXPECT_EQ(r.metrics.cut_edges, 1u);  // still two contiguous halves
  EXPECT_EQ(r.moved_poses, 3u);        // only the lost poses move
  EXPECT_EQ(r.metrics.max_block, 5u);
}

TEST(SurvivorRepartition, EachLostAgentOfFiveOnARandomGraph) {
  const GraphStructure g = random_structure(400, 7);
  const std::vector<int> owner = partition(g, 5);
  const std::size_t cut_before = compute_partition_metrics(g, owner, 5).cut_edges;
  for (int j = 0; j < 5; ++j) {
    const auto r = repartition_for_survivors(g, owner, 5, {j});
    expect_valid(g, owner, 5, {j}, r);
    // Grow keeps every survivor's block: exactly the lost poses move.
    EXPECT_EQ(r.moved_poses, r.lost_poses);
    for (std::size_t v = 0; v < g.num_vertices; ++v) {
      if (owner[v] != j) {
        EXPECT_EQ(r.owner[v], owner[v]);
      }
    }
    // Splitting one block among its neighbours cannot beat the old cut by much, nor should it
    // explode: every new cut edge touches a lost pose.
    EXPECT_LE(r.metrics.cut_edges, cut_before + g.total_edge_weight() / 5);
  }
}

TEST(SurvivorRepartition, Deterministic) {
  const GraphStructure g = random_structure(300, 3);
  const std::vector<int> owner = partition(g, 5);
  for (SurvivorStrategy s : {SurvivorStrategy::kGrow, SurvivorStrategy::kFresh}) {
    SurvivorRepartitionOptions o;
    o.strategy = s;
    const auto a = repartition_for_survivors(g, owner, 5, {1, 3}, o);
    const auto b = repartition_for_survivors(g, owner, 5, {3, 1}, o);
    EXPECT_EQ(a.owner, b.owner) << survivor_strategy_name(s);
    expect_valid(g, owner, 5, {1, 3}, a);
  }
}

TEST(SurvivorRepartition, FreshKeepsMostPosesWithTheirOwner) {
  const GraphStructure g = random_structure(400, 11);
  const std::vector<int> owner = partition(g, 5);
  SurvivorRepartitionOptions o;
  o.strategy = SurvivorStrategy::kFresh;
  const auto r = repartition_for_survivors(g, owner, 5, {4}, o);
  expect_valid(g, owner, 5, {4}, r);
  // Relabelling by overlap moves no more poses than keeping the partitioner's own labels.
  PartitionOptions po;
  po.parts = 4;
  po.preset = PartitionPreset::kEco;
  const std::vector<int> plain = partition_graph(g, po).assignment;
  const std::vector<int> survivors = {0, 1, 2, 3};
  std::size_t plain_moved = 0;
  for (std::size_t v = 0; v < g.num_vertices; ++v)
    plain_moved += survivors[static_cast<std::size_t>(plain[v])] != owner[v];
  EXPECT_LE(r.moved_poses, plain_moved);
  EXPECT_GE(r.moved_poses, r.lost_poses);
}

TEST(SurvivorRepartition, LostComponentUnreachableFromSurvivorsIsStillPlaced) {
  // Two components: 0-1-2-3 and 4-5-6-7; agent 1 owns the whole second one.
  std::vector<std::pair<std::size_t, std::size_t>> e = {{0, 1}, {1, 2}, {2, 3},
                                                        {4, 5}, {5, 6}, {6, 7}};
  const GraphStructure g = make_graph_structure(8, e, "two components");
  const std::vector<int> owner = {0, 0, 2, 2, 1, 1, 1, 1};
  const auto r = repartition_for_survivors(g, owner, 3, {1});
  expect_valid(g, owner, 3, {1}, r);
}

TEST(SurvivorRepartition, BadInputNamesTheProblem) {
  const GraphStructure g = path(6);
  const std::vector<int> owner = {0, 0, 1, 1, 2, 2};
  auto message = [&](auto f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { repartition_for_survivors(g, owner, 3, {}); }).find("no lost"),
            std::string::npos);
  EXPECT_NE(message([&] {
              repartition_for_survivors(g, owner, 3, {0, 1, 2});
            }).find("every"),
            std::string::npos);
  EXPECT_NE(message([&] { repartition_for_survivors(g, owner, 3, {5}); }).find("lost agent 5"),
            std::string::npos);
  EXPECT_NE(message([&] {
              repartition_for_survivors(g, {0, 1}, 3, {1});
            }).find("owner array"),
            std::string::npos);
  EXPECT_NE(message([&] {
              repartition_for_survivors(g, {0, 0, 1, 1, 2, 7}, 3, {1});
            }).find("pose 5"),
            std::string::npos);
  SurvivorRepartitionOptions o;
  o.eps = -1;
  EXPECT_NE(message([&] { repartition_for_survivors(g, owner, 3, {1}, o); }).find("eps"),
            std::string::npos);
  EXPECT_THROW(parse_survivor_strategy("magic"), InputError);
}

TEST(ReplicaPlan, MostCutNeighbourFirstThenCyclicFill) {
  // Poses 0..5: agent 0 = {0, 1}, agent 1 = {2, 3}, agent 2 = {4}, agent 3 = {5}.
  const std::vector<std::uint32_t> owner = {0, 0, 1, 1, 2, 3};
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> s = {{0, 1}, {1, 2}, {1, 3},
                                                                  {0, 4}, {3, 4}, {4, 5}};
  const auto h1 = replica_holders(s, owner, 4, 1);
  EXPECT_EQ(h1[0], (std::vector<std::uint32_t>{1}));  // 2 cut edges to agent 1, 1 to agent 2
  EXPECT_EQ(h1[3], (std::vector<std::uint32_t>{2}));
  const auto h3 = replica_holders(s, owner, 4, 3);
  EXPECT_EQ(h3[0], (std::vector<std::uint32_t>{1, 2, 3}));  // 3 joins by cyclic fill
  EXPECT_EQ(h3[3], (std::vector<std::uint32_t>{2, 0, 1}));
  for (std::uint32_t a = 0; a < 4; ++a)
    for (auto b : h3[a]) EXPECT_NE(a, b);
  EXPECT_EQ(replica_holders(s, owner, 4, 9)[1].size(), 3u);  // at most N - 1
  EXPECT_EQ(replicas_kept_by(h1, 0), (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ(replicas_kept_by(h1, 2), (std::vector<std::uint32_t>{3}));
  EXPECT_THROW(replica_holders({{0, 9}}, owner, 4, 1), InputError);
}

}  // namespace
}  // namespace tessera
