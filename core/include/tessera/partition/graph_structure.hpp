#pragma once
// The structure of a pose graph as the partitioner sees it: an undirected graph in CSR form
// whose vertices are poses (unit weight) and whose edges are the distinct pose pairs joined by
// at least one measurement, weighted by how many measurements join them. Measurement values
// never enter here, only which poses they connect.

#include <cstddef>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <utility>
#include <vector>

namespace tessera {

struct GraphStructure {
  std::size_t num_vertices = 0;  ///< n: vertices are 0..n-1.
  std::vector<std::size_t>
      offsets;  ///< n+1 entries: neighbours of v are [offsets[v], offsets[v+1]).
  std::vector<std::size_t>
      neighbors;  ///< Each undirected edge appears twice (u in v's list, v in u's).
  std::vector<std::size_t>
      weights;         ///< Edge weight (>= 1) = number of measurements joining the pair.
  std::string source;  ///< File path or description, for messages.

  /// Distinct vertex pairs joined by at least one edge.
  std::size_t num_pairs() const { return neighbors.size() / 2; }
  /// Sum of edge weights = number of measurements (parallel ones included).
  std::size_t total_edge_weight() const;
  std::size_t degree(std::size_t v) const { return offsets[v + 1] - offsets[v]; }
};

/// Builds the structure from a list of (possibly repeated, possibly backwards) vertex pairs with
/// a weight each; repeated pairs are merged and their weights added. Neighbour lists come out
/// sorted by id. Throws InputError (naming `source`) on an id >= n, a self loop or weight 0.
GraphStructure make_graph_structure(std::size_t n,
                                    const std::vector<std::pair<std::size_t, std::size_t>>& pairs,
                                    const std::vector<std::size_t>& pair_weights,
                                    const std::string& source);

/// Same with every pair of weight 1 (one measurement each).
GraphStructure make_graph_structure(std::size_t n,
                                    const std::vector<std::pair<std::size_t, std::size_t>>& pairs,
                                    const std::string& source);

/// The structure of a pose graph: one vertex per pose, each measurement adds 1 to the weight of
/// the edge {i, j}. Uses only num_poses and each measurement's i and j.
GraphStructure graph_structure_from_pose_graph(const PoseGraph& graph);

}  // namespace tessera
