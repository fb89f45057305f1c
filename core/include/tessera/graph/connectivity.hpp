#pragma once
// Connectivity of a pose graph's measurement structure.

#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <utility>
#include <vector>

namespace tessera {

/// Component label (0..k-1, in order of the smallest pose id) for each of the graph's poses.
std::vector<std::size_t> connected_components(const PoseGraph& graph);

/// The same labels for a graph given by adjacency lists (vertex v's neighbours in
/// adjacency[v]; neighbours out of range are ignored), e.g. a partition's block graph.
std::vector<std::size_t> connected_components(const std::vector<std::vector<int>>& adjacency);

/// The same labels for vertices 0..num_vertices-1 joined by `edges` (pairs of vertex ids, in
/// either order; a pair with an end out of range is ignored), e.g. a robot's own measurements.
std::vector<std::size_t> connected_components(
    std::size_t num_vertices, const std::vector<std::pair<std::size_t, std::size_t>>& edges);

/// Number of connected components (1 for a connected graph; n for a graph with no edges).
std::size_t count_components(const PoseGraph& graph);

}  // namespace tessera
