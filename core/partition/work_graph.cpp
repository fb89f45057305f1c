#include "partition/work_graph.hpp"

#include <numeric>

namespace tessera::partition_detail {

WorkGraph to_work_graph(const GraphStructure& g) {
  WorkGraph w;
  w.n = static_cast<int>(g.num_vertices);
  w.xadj.assign(g.offsets.begin(), g.offsets.end());
  w.adj.assign(g.neighbors.begin(), g.neighbors.end());
  w.ew.assign(g.weights.begin(), g.weights.end());
  w.vw.assign(static_cast<std::size_t>(w.n), 1);
  w.total_vw = w.n;
  return w;
}

WorkGraph contract(const WorkGraph& g, const std::vector<int>& cluster, int num_clusters) {
  WorkGraph c;
  c.n = num_clusters;
  c.vw.assign(static_cast<std::size_t>(num_clusters), 0);
  c.total_vw = g.total_vw;
  // Members of each cluster, by counting sort.
  std::vector<int> start(static_cast<std::size_t>(num_clusters) + 1, 0);
  for (int v = 0; v < g.n; ++v) {
    ++start[cluster[v] + 1];
    c.vw[cluster[v]] += g.vw[v];
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int> members(static_cast<std::size_t>(g.n));
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int v = 0; v < g.n; ++v) members[fill[cluster[v]]++] = v;
  }
  c.xadj.assign(static_cast<std::size_t>(num_clusters) + 1, 0);
  c.adj.reserve(g.adj.size() / 2);
  c.ew.reserve(g.adj.size() / 2);
  std::vector<int> slot(static_cast<std::size_t>(num_clusters),
                        -1);  // position of neighbour in adj
  for (int cv = 0; cv < num_clusters; ++cv) {
    const int first = static_cast<int>(c.adj.size());
    for (int k = start[cv]; k < start[cv + 1]; ++k) {
      const int v = members[k];
      for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
        const int cu = cluster[g.adj[e]];
        if (cu == cv) continue;
        if (slot[cu] >= first) {
          c.ew[slot[cu]] += g.ew[e];
        } else {
          slot[cu] = static_cast<int>(c.adj.size());
          c.adj.push_back(cu);
          c.ew.push_back(g.ew[e]);
        }
      }
    }
    c.xadj[cv + 1] = static_cast<int>(c.adj.size());
  }
  return c;
}

long long edge_cut(const WorkGraph& g, const std::vector<int>& part) {
  long long cut = 0;
  for (int v = 0; v < g.n; ++v)
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e)
      if (part[g.adj[e]] != part[v]) cut += g.ew[e];
  return cut / 2;
}

std::vector<long long> block_weights(const WorkGraph& g, const std::vector<int>& part, int k) {
  std::vector<long long> w(static_cast<std::size_t>(k), 0);
  for (int v = 0; v < g.n; ++v) w[part[v]] += g.vw[v];
  return w;
}

std::vector<int> random_order(int n, Rng& rng) {
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  for (int i = n - 1; i > 0; --i) std::swap(order[i], order[rng.below(i + 1)]);
  return order;
}

}  // namespace tessera::partition_detail
