#include <algorithm>
#include <numeric>
#include <tessera/graph/connectivity.hpp>

namespace tessera {
namespace {

std::size_t find_root(std::vector<std::size_t>& parent, std::size_t v) {
  while (parent[v] != v) {
    parent[v] = parent[parent[v]];  // path halving keeps trees shallow
    v = parent[v];
  }
  return v;
}

// Component labels in order of the smallest vertex, from the union-find forest `parent`.
std::vector<std::size_t> labels_of(std::vector<std::size_t>& parent) {
  const std::size_t n = parent.size();
  std::vector<std::size_t> label(n), root_label(n, n);
  std::size_t next = 0;
  for (std::size_t v = 0; v < n; ++v) {
    std::size_t r = find_root(parent, v);
    if (root_label[r] == n) root_label[r] = next++;
    label[v] = root_label[r];
  }
  return label;
}

void join(std::vector<std::size_t>& parent, std::size_t u, std::size_t v) {
  const std::size_t a = find_root(parent, u), b = find_root(parent, v);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

}  // namespace

std::vector<std::size_t> connected_components(const PoseGraph& graph) {
  const std::size_t n = graph.num_poses;
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& m : graph.measurements)
    if (m.i < n && m.j < n) join(parent, m.i, m.j);
  return labels_of(parent);
}

std::vector<std::size_t> connected_components(const std::vector<std::vector<int>>& adjacency) {
  const std::size_t n = adjacency.size();
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t v = 0; v < n; ++v)
    for (int u : adjacency[v])
      if (u >= 0 && static_cast<std::size_t>(u) < n) join(parent, v, static_cast<std::size_t>(u));
  return labels_of(parent);
}

std::vector<std::size_t> connected_components(
    std::size_t num_vertices, const std::vector<std::pair<std::size_t, std::size_t>>& edges) {
  std::vector<std::size_t> parent(num_vertices);
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [u, v] : edges)
    if (u < num_vertices && v < num_vertices) join(parent, u, v);
  return labels_of(parent);
}

std::size_t count_components(const PoseGraph& graph) {
  auto labels = connected_components(graph);
  std::size_t k = 0;
  for (auto l : labels) k = std::max(k, l + 1);
  return k;
}

}  // namespace tessera
