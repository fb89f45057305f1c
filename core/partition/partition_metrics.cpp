#include <algorithm>
#include <cmath>
#include <string>
#include <tessera/partition/partition_metrics.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

std::size_t max_block_size(std::size_t n, int parts, double eps) {
  const std::size_t p = static_cast<std::size_t>(std::max(parts, 1));
  const std::size_t ceil_avg = (n + p - 1) / p;
  // The small guard keeps e.g. 1.03 * 100 from rounding down to 102.
  return static_cast<std::size_t>(std::floor((1.0 + eps) * static_cast<double>(ceil_avg) + 1e-9));
}

PartitionMetrics compute_partition_metrics(const GraphStructure& graph,
                                           const std::vector<int>& assignment, int parts) {
  const std::size_t n = graph.num_vertices;
  if (parts < 1) throw InputError("partition metrics: parts must be >= 1");
  if (assignment.size() != n)
    throw InputError("partition metrics: assignment has " + std::to_string(assignment.size()) +
                     " entries for " + std::to_string(n) + " vertices");
  PartitionMetrics m;
  m.parts = static_cast<std::size_t>(parts);
  m.num_vertices = n;
  m.block_sizes.assign(m.parts, 0);
  for (std::size_t v = 0; v < n; ++v) {
    if (assignment[v] < 0 || assignment[v] >= parts)
      throw InputError("partition metrics: vertex " + std::to_string(v) + " has block id " +
                       std::to_string(assignment[v]) + ", outside 0.." + std::to_string(parts - 1));
    ++m.block_sizes[static_cast<std::size_t>(assignment[v])];
  }
  std::vector<std::size_t> seen(m.parts, n);  // seen[b] == v: v already counted block b
  std::size_t volume = 0, cut_w = 0, cut_p = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const int bv = assignment[v];
    bool boundary = false;
    for (std::size_t e = graph.offsets[v]; e < graph.offsets[v + 1]; ++e) {
      const int bu = assignment[graph.neighbors[e]];
      if (bu == bv) continue;
      boundary = true;
      cut_w += graph.weights[e];
      ++cut_p;
      if (seen[static_cast<std::size_t>(bu)] != v) {
        seen[static_cast<std::size_t>(bu)] = v;
        ++volume;
      }
    }
    if (boundary) ++m.boundary_vertices;
  }
  m.cut_edges = cut_w / 2;  // every cut edge was seen from both ends
  m.cut_pairs = cut_p / 2;
  m.max_block = n ? *std::max_element(m.block_sizes.begin(), m.block_sizes.end()) : 0;
  if (n > 0) {
    const double avg = static_cast<double>(n) / parts;
    const double ceil_avg = static_cast<double>((n + m.parts - 1) / m.parts);
    m.imbalance = static_cast<double>(m.max_block) / avg - 1.0;
    m.max_block_ratio = static_cast<double>(m.max_block) / ceil_avg;
    m.cvolume = static_cast<double>(volume) / static_cast<double>(n);
  }
  return m;
}

}  // namespace tessera
