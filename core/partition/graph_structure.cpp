#include <algorithm>
#include <numeric>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

std::size_t GraphStructure::total_edge_weight() const {
  return std::accumulate(weights.begin(), weights.end(), std::size_t{0}) / 2;
}

GraphStructure make_graph_structure(std::size_t n,
                                    const std::vector<std::pair<std::size_t, std::size_t>>& pairs,
                                    const std::vector<std::size_t>& pair_weights,
                                    const std::string& source) {
  if (pair_weights.size() != pairs.size())
    throw InputError(source, 0, "internal: one weight per vertex pair expected");
  // Each pair goes into both endpoints' lists; sorting each list then merges duplicates.
  std::vector<std::size_t> count(n + 1, 0);
  for (std::size_t e = 0; e < pairs.size(); ++e) {
    const auto [a, b] = pairs[e];
    if (a >= n || b >= n)
      throw InputError(source, 0,
                       "vertex id " + std::to_string(std::max(a, b)) + " out of range (graph has " +
                           std::to_string(n) + " vertices)");
    if (a == b) throw InputError(source, 0, "self loop on vertex " + std::to_string(a));
    if (pair_weights[e] == 0)
      throw InputError(source, 0,
                       "edge " + std::to_string(a) + "-" + std::to_string(b) + " has weight 0");
    ++count[a + 1];
    ++count[b + 1];
  }
  std::partial_sum(count.begin(), count.end(), count.begin());
  std::vector<std::pair<std::size_t, std::size_t>> entries(count[n]);  // (neighbour, weight)
  std::vector<std::size_t> fill(count.begin(), count.end() - 1);
  for (std::size_t e = 0; e < pairs.size(); ++e) {
    const auto [a, b] = pairs[e];
    entries[fill[a]++] = {b, pair_weights[e]};
    entries[fill[b]++] = {a, pair_weights[e]};
  }
  GraphStructure g;
  g.num_vertices = n;
  g.source = source;
  g.offsets.assign(n + 1, 0);
  g.neighbors.reserve(entries.size());
  g.weights.reserve(entries.size());
  for (std::size_t v = 0; v < n; ++v) {
    auto first = entries.begin() + static_cast<std::ptrdiff_t>(count[v]);
    auto last = entries.begin() + static_cast<std::ptrdiff_t>(count[v + 1]);
    std::sort(first, last);
    for (auto it = first; it != last; ++it) {
      if (!g.neighbors.empty() && g.neighbors.size() > g.offsets[v] &&
          g.neighbors.back() == it->first) {
        g.weights.back() += it->second;
      } else {
        g.neighbors.push_back(it->first);
        g.weights.push_back(it->second);
      }
    }
    g.offsets[v + 1] = g.neighbors.size();
  }
  return g;
}

GraphStructure make_graph_structure(std::size_t n,
                                    const std::vector<std::pair<std::size_t, std::size_t>>& pairs,
                                    const std::string& source) {
  return make_graph_structure(n, pairs, std::vector<std::size_t>(pairs.size(), 1), source);
}

GraphStructure graph_structure_from_pose_graph(const PoseGraph& graph) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  pairs.reserve(graph.measurements.size());
  for (const auto& m : graph.measurements) pairs.emplace_back(m.i, m.j);
  return make_graph_structure(graph.num_poses, pairs,
                              graph.source.empty() ? std::string("pose graph") : graph.source);
}

}  // namespace tessera
