// Graph structure construction, partition metrics, the balance bound and the sequential split.

#include <gtest/gtest.h>

#include <cmath>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partition_metrics.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/util/input_error.hpp>

namespace {

using namespace tessera;

TEST(GraphStructure, MergesParallelAndBackwardMeasurements) {
  PoseGraph pg;
  pg.num_poses = 4;
  for (auto [i, j] : {std::pair<std::size_t, std::size_t>{0, 1}, {1, 0}, {1, 2}, {2, 3}, {0, 1}}) {
    Measurement m;
    m.i = i;
    m.j = j;
    pg.measurements.push_back(m);
  }
  const GraphStructure g = graph_structure_from_pose_graph(pg);
  EXPECT_EQ(g.num_vertices, 4u);
  EXPECT_EQ(g.num_pairs(), 3u);
  EXPECT_EQ(g.total_edge_weight(), 5u);
  ASSERT_EQ(g.degree(0), 1u);
  EXPECT_EQ(g.neighbors[g.offsets[0]], 1u);
  EXPECT_EQ(g.weights[g.offsets[0]], 3u);  // 0-1, 1-0, 0-1
  ASSERT_EQ(g.degree(1), 2u);              // sorted neighbour lists
  EXPECT_EQ(g.neighbors[g.offsets[1]], 0u);
  EXPECT_EQ(g.neighbors[g.offsets[1] + 1], 2u);
}

TEST(GraphStructure, RejectsBadPairs) {
  EXPECT_THROW(make_graph_structure(3, {{0, 3}}, "x"), InputError);
  EXPECT_THROW(make_graph_structure(3, {{1, 1}}, "x"), InputError);
  EXPECT_THROW(make_graph_structure(3, {{0, 1}}, {0}, "x"), InputError);
}

TEST(PartitionMetrics, CountsCutMeasurementsPairsAndVolume) {
  // Path 0-1-2-3 where 1-2 carries two measurements, plus 0-3. Blocks {0,1} {2,3}.
  const GraphStructure g = make_graph_structure(4, {{0, 1}, {1, 2}, {1, 2}, {2, 3}, {0, 3}}, "g");
  const PartitionMetrics m = compute_partition_metrics(g, {0, 0, 1, 1}, 2);
  EXPECT_EQ(m.cut_edges, 3u);  // 1-2 twice and 0-3
  EXPECT_EQ(m.cut_pairs, 2u);
  EXPECT_EQ(m.block_sizes, (std::vector<std::size_t>{2, 2}));
  EXPECT_EQ(m.max_block, 2u);
  EXPECT_DOUBLE_EQ(m.imbalance, 0.0);
  EXPECT_DOUBLE_EQ(m.max_block_ratio, 1.0);
  EXPECT_DOUBLE_EQ(m.cvolume, 1.0);  // every vertex has a neighbour in the other block
  EXPECT_EQ(m.boundary_vertices, 4u);
}

TEST(PartitionMetrics, VolumeCountsEachOtherBlockOnce) {
  // Star: centre 0 with leaves 1..4 in blocks 1,1,2,0 -> centre sees 2 other blocks.
  const GraphStructure g = make_graph_structure(5, {{0, 1}, {0, 2}, {0, 3}, {0, 4}}, "star");
  const PartitionMetrics m = compute_partition_metrics(g, {0, 1, 1, 2, 0}, 3);
  EXPECT_EQ(m.cut_edges, 3u);
  // v0: blocks 1 and 2 -> 2; v1, v2, v3: 1 each; v4: 0.
  EXPECT_DOUBLE_EQ(m.cvolume, 5.0 / 5.0);
  EXPECT_EQ(m.block_sizes, (std::vector<std::size_t>{2, 2, 1}));
  EXPECT_NEAR(m.imbalance, 2.0 / (5.0 / 3.0) - 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.max_block_ratio, 1.0);  // ceil(5/3) = 2
}

TEST(PartitionMetrics, RejectsBadAssignments) {
  const GraphStructure g = make_graph_structure(3, {{0, 1}}, "g");
  EXPECT_THROW(compute_partition_metrics(g, {0, 1}, 2), InputError);
  EXPECT_THROW(compute_partition_metrics(g, {0, 1, 2}, 2), InputError);
  EXPECT_THROW(compute_partition_metrics(g, {0, -1, 1}, 2), InputError);
}

TEST(PartitionMetrics, BalanceBound) {
  EXPECT_EQ(max_block_size(100, 5, 0.03), 20u);      // floor(1.03 * 20) = 20
  EXPECT_EQ(max_block_size(10195, 5, 0.03), 2100u);  // floor(1.03 * 2039)
  EXPECT_EQ(max_block_size(1000, 10, 0.03), 103u);   // no rounding down to 102
  EXPECT_EQ(max_block_size(7, 2, 0.0), 4u);
}

TEST(SequentialPartition, ContiguousRangesDifferingByAtMostOne) {
  const std::vector<int> p = sequential_partition(11, 4);
  EXPECT_EQ(p, (std::vector<int>{0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3}));
  for (std::size_t n : {5u, 64u, 1000u, 1001u})
    for (int parts : {1, 2, 3, 5, 64}) {
      if (static_cast<std::size_t>(parts) > n) continue;
      const auto q = sequential_partition(n, parts);
      std::vector<std::size_t> sizes(static_cast<std::size_t>(parts), 0);
      for (std::size_t v = 0; v < n; ++v) {
        ++sizes[static_cast<std::size_t>(q[v])];
        if (v > 0) {
          EXPECT_LE(q[v - 1], q[v]);
        }
      }
      const auto [lo, hi] = std::minmax_element(sizes.begin(), sizes.end());
      EXPECT_LE(*hi - *lo, 1u);
      EXPECT_GE(*lo, 1u);
    }
}

}  // namespace
