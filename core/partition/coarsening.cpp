#include "partition/coarsening.hpp"

namespace tessera::partition_detail {
namespace {

// Heavy-edge matching; returns the number of clusters written into `cluster`.
int heavy_edge_matching(const WorkGraph& g, const std::vector<int>* label, int max_vw, Rng& rng,
                        std::vector<int>& cluster) {
  std::vector<int> mate(static_cast<std::size_t>(g.n), -1);
  for (int u : random_order(g.n, rng)) {
    if (mate[u] >= 0) continue;
    int best = -1;
    double best_rating = -1.0;
    for (int e = g.xadj[u]; e < g.xadj[u + 1]; ++e) {
      const int v = g.adj[e];
      if (mate[v] >= 0 || g.vw[u] + g.vw[v] > max_vw) continue;
      if (label && (*label)[u] != (*label)[v]) continue;
      const double w = g.ew[e];
      const double rating = w * w / (static_cast<double>(g.vw[u]) * g.vw[v]);
      if (rating > best_rating || (rating == best_rating && (rng.next() & 1))) {
        best_rating = rating;
        best = v;
      }
    }
    mate[u] = best >= 0 ? best : u;
    if (best >= 0) mate[best] = u;
  }
  cluster.assign(static_cast<std::size_t>(g.n), -1);
  int cn = 0;
  for (int v = 0; v < g.n; ++v) {
    if (cluster[v] >= 0) continue;
    cluster[v] = cn;
    cluster[mate[v]] = cn;
    ++cn;
  }
  return cn;
}

// Size-constrained label propagation (clusters of weight <= max_vw); returns the cluster count.
int label_propagation(const WorkGraph& g, const std::vector<int>* label, int max_vw, int rounds,
                      Rng& rng, std::vector<int>& cluster) {
  std::vector<int> cl(static_cast<std::size_t>(g.n));
  std::vector<long long> cw(static_cast<std::size_t>(g.n));
  for (int v = 0; v < g.n; ++v) {
    cl[v] = v;
    cw[v] = g.vw[v];
  }
  std::vector<long long> conn(static_cast<std::size_t>(g.n), 0);
  std::vector<int> touched;
  const std::vector<int> order = random_order(g.n, rng);
  for (int r = 0; r < rounds; ++r) {
    int changed = 0;
    for (int v : order) {
      touched.clear();
      for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
        const int u = g.adj[e];
        if (label && (*label)[u] != (*label)[v]) continue;
        if (conn[cl[u]] == 0) touched.push_back(cl[u]);
        conn[cl[u]] += g.ew[e];
      }
      int best = cl[v];
      long long best_w = conn[cl[v]];
      for (int c : touched) {
        if (c != cl[v] && cw[c] + g.vw[v] <= max_vw &&
            (conn[c] > best_w || (conn[c] == best_w && (rng.next() & 1)))) {
          best = c;
          best_w = conn[c];
        }
      }
      for (int c : touched) conn[c] = 0;
      if (best != cl[v]) {
        cw[cl[v]] -= g.vw[v];
        cw[best] += g.vw[v];
        cl[v] = best;
        ++changed;
      }
    }
    if (changed == 0) break;
  }
  // Renumber clusters densely.
  std::vector<int> id(static_cast<std::size_t>(g.n), -1);
  cluster.assign(static_cast<std::size_t>(g.n), -1);
  int cn = 0;
  for (int v = 0; v < g.n; ++v) {
    if (id[cl[v]] < 0) id[cl[v]] = cn++;
    cluster[v] = id[cl[v]];
  }
  return cn;
}

}  // namespace

Hierarchy coarsen(const WorkGraph& fine, const std::vector<int>* label,
                  const CoarseningParams& params, Rng& rng) {
  Hierarchy h;
  std::vector<int> level_label;
  if (label) level_label = *label;
  for (int level = 0; level < 64; ++level) {
    const WorkGraph& g = h.top(fine);
    if (g.n <= params.stop_vertices) break;
    std::vector<int> cluster;
    const std::vector<int>* lab = label ? &level_label : nullptr;
    const int cn = params.label_propagation_rounds > 0
                       ? label_propagation(g, lab, params.max_vertex_weight,
                                           params.label_propagation_rounds, rng, cluster)
                       : heavy_edge_matching(g, lab, params.max_vertex_weight, rng, cluster);
    // Too little progress: the constraints (labels, weights) leave nothing worth contracting.
    if (cn > g.n - g.n / 20 || cn == g.n) break;
    if (label) {
      std::vector<int> coarse_label(static_cast<std::size_t>(cn));
      for (int v = 0; v < g.n; ++v) coarse_label[cluster[v]] = level_label[v];
      level_label.swap(coarse_label);
    }
    WorkGraph c = contract(g, cluster, cn);
    h.maps.push_back(std::move(cluster));
    h.coarse.push_back(std::move(c));
  }
  return h;
}

}  // namespace tessera::partition_detail
