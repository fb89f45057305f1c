// Connected components of a pose graph, of a graph given by adjacency lists (a partition's
// block graph) and of one given by an edge list: labels 0..k-1 in order of the smallest vertex,
// the same for every form.
#include <gtest/gtest.h>

#include <tessera/graph/connectivity.hpp>
#include <vector>

namespace tessera {
namespace {

TEST(Connectivity, AdjacencyListsGetTheLabelsOfTheSameGraphsMeasurements) {
  // Vertices 0-2 joined (through 2-0), 3 alone, 4-5 joined: three components.
  PoseGraph g;
  g.num_poses = 6;
  for (auto [i, j] : std::vector<std::pair<std::size_t, std::size_t>>{{2, 0}, {1, 2}, {5, 4}}) {
    Measurement m;
    m.i = i;
    m.j = j;
    g.measurements.push_back(m);
  }
  const std::vector<std::vector<int>> adjacency{{2}, {2}, {0, 1}, {}, {5}, {4}};
  const std::vector<std::size_t> expected{0, 0, 0, 1, 2, 2};
  EXPECT_EQ(connected_components(g), expected);
  EXPECT_EQ(connected_components(adjacency), expected);
  EXPECT_EQ(count_components(g), 3u);
}

TEST(Connectivity, NeighboursOutOfRangeAreIgnored) {
  const std::vector<std::vector<int>> adjacency{{1, 7, -1}, {0}, {}};
  EXPECT_EQ(connected_components(adjacency), (std::vector<std::size_t>{0, 0, 1}));
}

TEST(Connectivity, EdgeListsGetTheLabelsOfTheSameGraphsMeasurements) {
  // The graph of the first test as pairs, some written high end first: the same labels.
  const std::vector<std::pair<std::size_t, std::size_t>> edges{{2, 0}, {1, 2}, {5, 4}};
  EXPECT_EQ(connected_components(6, edges), (std::vector<std::size_t>{0, 0, 0, 1, 2, 2}));
  EXPECT_EQ(connected_components(3, {}), (std::vector<std::size_t>{0, 1, 2}));
}

TEST(Connectivity, EdgesWithAnEndOutOfRangeAreIgnored) {
  const std::vector<std::pair<std::size_t, std::size_t>> edges{{0, 1}, {1, 3}, {7, 2}};
  EXPECT_EQ(connected_components(3, edges), (std::vector<std::size_t>{0, 0, 1}));
}

}  // namespace
}  // namespace tessera
