#include "partition/initial_partitioning.hpp"

#include <algorithm>
#include <cmath>

#include "partition/gain_queue.hpp"

namespace tessera::partition_detail {
namespace {

// The subgraph induced by `verts` (ids of g), in the order given.
WorkGraph induced(const WorkGraph& g, const std::vector<int>& verts, std::vector<int>& local) {
  WorkGraph s;
  s.n = static_cast<int>(verts.size());
  s.xadj.assign(static_cast<std::size_t>(s.n) + 1, 0);
  s.vw.resize(static_cast<std::size_t>(s.n));
  for (int i = 0; i < s.n; ++i) local[verts[i]] = i;
  for (int i = 0; i < s.n; ++i) {
    const int v = verts[i];
    s.vw[i] = g.vw[v];
    s.total_vw += g.vw[v];
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (local[u] < 0) continue;
      s.adj.push_back(local[u]);
      s.ew.push_back(g.ew[e]);
    }
    s.xadj[i + 1] = static_cast<int>(s.adj.size());
  }
  for (int v : verts) local[v] = -1;
  return s;
}

// Grows block 0 from a random vertex until its weight is as close to `target` as it gets;
// everything else is block 1.
std::vector<int> greedy_growing(const WorkGraph& g, long long target, Rng& rng) {
  std::vector<int> part(static_cast<std::size_t>(g.n), 1);
  std::vector<long long> to_region(static_cast<std::size_t>(g.n), 0),
      wdeg(static_cast<std::size_t>(g.n), 0);
  for (int v = 0; v < g.n; ++v)
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) wdeg[v] += g.ew[e];
  GainQueue queue(g.n);
  long long weight = 0;
  auto add = [&](int v) {
    part[v] = 0;
    weight += g.vw[v];
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (part[u] == 0) continue;
      to_region[u] += g.ew[e];
      queue.set(u, (2 * to_region[u] - wdeg[u]) * 1024 + static_cast<long long>(rng.next() & 1023));
    }
  };
  int start = rng.below(g.n);
  while (weight < target) {
    int v;
    if (queue.empty()) {  // new component (or first vertex): restart from a random outside vertex
      while (part[start] == 0) start = (start + 1) % g.n;
      v = start;
    } else {
      v = queue.pop();
    }
    if (weight > 0 && weight + g.vw[v] - target > target - weight) break;  // overshoot is worse
    add(v);
  }
  return part;
}

void recursive_bisection(const WorkGraph& g, const std::vector<int>& verts, int k, int first_block,
                         const InitialParams& params, Rng& rng, std::vector<int>& part,
                         std::vector<int>& local) {
  if (k == 1) {
    for (int v : verts) part[v] = first_block;
    return;
  }
  const int k0 = k / 2, k1 = k - k0;
  WorkGraph s = induced(g, verts, local);
  const long long target0 = s.total_vw * k0 / k;
  const long long target1 = s.total_vw - target0;
  int max_vw = 1;
  for (int w : s.vw) max_vw = std::max(max_vw, w);
  const std::vector<long long> ub = {
      std::max<long long>(static_cast<long long>(std::ceil(target0 * (1.0 + params.eps))),
                          target0 + max_vw),
      std::max<long long>(static_cast<long long>(std::ceil(target1 * (1.0 + params.eps))),
                          target1 + max_vw)};
  std::vector<int> best;
  long long best_cut = -1;
  bool best_ok = false;
  for (int t = 0; t < std::max(1, params.bisection_tries); ++t) {
    std::vector<int> p = s.n > 0 ? greedy_growing(s, target0, rng) : std::vector<int>();
    const bool ok = rebalance(s, 2, p, ub);
    const long long cut = kway_fm(s, 2, p, ub, params.fm, rng);
    if (best_cut < 0 || (ok && !best_ok) || (ok == best_ok && cut < best_cut)) {
      best = std::move(p);
      best_cut = cut;
      best_ok = ok;
    }
  }
  std::vector<int> side[2];
  for (int i = 0; i < s.n; ++i) side[best[i]].push_back(verts[i]);
  recursive_bisection(g, side[0], k0, first_block, params, rng, part, local);
  recursive_bisection(g, side[1], k1, first_block + k0, params, rng, part, local);
}

}  // namespace

std::vector<int> initial_partition(const WorkGraph& g, int k, const std::vector<long long>& ub,
                                   const InitialParams& params, Rng& rng) {
  std::vector<int> all(static_cast<std::size_t>(g.n));
  for (int v = 0; v < g.n; ++v) all[v] = v;
  std::vector<int> local(static_cast<std::size_t>(g.n), -1);
  std::vector<int> best;
  long long best_cut = -1;
  bool best_ok = false;
  int repeats = std::max(1, params.repeats);
  if (params.repeat_budget > 0 && g.n > 0) {
    const int scaled =
        static_cast<int>(std::lround(static_cast<double>(params.repeat_budget) / g.n));
    repeats = std::clamp(scaled, std::min(std::max(1, params.min_repeats), repeats), repeats);
  }
  for (int r = 0; r < repeats; ++r) {
    std::vector<int> part(static_cast<std::size_t>(g.n), 0);
    recursive_bisection(g, all, k, 0, params, rng, part, local);
    const bool ok = rebalance(g, k, part, ub);
    const long long cut = kway_fm(g, k, part, ub, params.fm, rng);
    if (best_cut < 0 || (ok && !best_ok) || (ok == best_ok && cut < best_cut)) {
      best = std::move(part);
      best_cut = cut;
      best_ok = ok;
    }
  }
  return best;
}

}  // namespace tessera::partition_detail
