#include "partition/flow_refinement.hpp"

#include <algorithm>
#include <climits>
#include <map>
#include <utility>

namespace tessera::partition_detail {
namespace {

// Dinic's max flow on a small network. Arcs are collected first and then laid out per node
// (CSR: a node's arcs are contiguous, each with the index of its reverse arc), and the level BFS
// stops as soon as it reaches t. The flows are ~60 % of a strong / highest run (perf, rim), most
// of it in the BFS and the augmenting DFS, which scan the whole network once per phase; the two
// changes made strong on rim ~12 % faster (session 9). Which maximum flow is found does not
// matter: the residual sets used below (what s reaches, what reaches t) are the same for every
// maximum flow, so every partition is bit-identical to the linked-list version's. Session 11
// (speed11) labels levels by the distance to t instead of from s (see label_distances_to), which
// took the augmenting search from ~22 % of a highest run on rim to ~3 %.
class FlowNetwork {
 public:
  /// Empties the network and gives it n nodes; keeps the buffers' memory, since one network
  /// is rebuilt for every block pair and corridor size of a round (session 11, speed11).
  void reset(int n) {
    first_.assign(static_cast<std::size_t>(n) + 1, 0);
    level_.resize(static_cast<std::size_t>(n));
    it_.resize(static_cast<std::size_t>(n));
    pending_.clear();
  }
  /// Adds the arc pair u -> v (capacity c_uv) and v -> u (c_vu). Only before max_flow().
  void add(int u, int v, long long c_uv, long long c_vu) {
    pending_.push_back({u, v, c_uv, c_vu});
    ++first_[u + 1];
    ++first_[v + 1];
  }
  long long max_flow(int s, int t) {
    build();
    long long flow = 0;
    while (label_distances_to(t, s)) {
      std::copy(first_.begin(), first_.end() - 1, it_.begin());
      while (long long f = dfs(s, t, LLONG_MAX)) flow += f;
    }
    return flow;
  }
  /// Nodes reachable from s in the residual network.
  std::vector<char> reachable_from(int s) const { return residual_search(s, false); }
  /// Nodes that can reach t in the residual network.
  std::vector<char> reaching(int t) const { return residual_search(t, true); }

 private:
  struct Pending {
    int u, v;
    long long c_uv, c_vu;
  };
  // One arc with everything the level search and the augmenting search read together: one
  // 24-byte record instead of parallel arrays (fewer cache lines per scanned arc).
  //
  // `back` mirrors the reverse arc's capacity so that searches against the arc direction (the
  // distance labels towards t, the set reaching t) stay within the record.
  struct Arc {
    int to, rev;
    long long cap, back;
  };

  void build() {
    const std::size_t n = first_.size() - 1;
    for (std::size_t v = 0; v < n; ++v) first_[v + 1] += first_[v];
    arcs_.resize(2 * pending_.size());
    it_.assign(first_.begin(), first_.end() - 1);  // fill positions while building
    for (const Pending& p : pending_) {
      const int a = it_[p.u]++, b = it_[p.v]++;
      arcs_[a] = {p.v, b, p.c_uv, p.c_vu};
      arcs_[b] = {p.u, a, p.c_vu, p.c_uv};
    }
    pending_.clear();
  }
  // Depth-first search over arcs with residual capacity, forwards from `from` or (reverse)
  // backwards into it.
  std::vector<char> residual_search(int from, bool reverse) const {
    std::vector<char> seen(first_.size() - 1, 0);
    std::vector<int> stack = {from};
    seen[from] = 1;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (int a = first_[v]; a < first_[v + 1]; ++a) {
        const Arc& arc = arcs_[a];
        // Backwards, the arc arc.to -> v is the reverse of a; usable if it has capacity.
        const long long c = reverse ? arc.back : arc.cap;
        if (c > 0 && !seen[arc.to]) {
          seen[arc.to] = 1;
          stack.push_back(arc.to);
        }
      }
    }
    return seen;
  }
  // Level search backwards from t: level_[v] = residual distance from v to t, for every node
  // closer to t than s (and s itself). Returns whether s can reach t. Labelling by the distance
  // to t (not from s) means that every node the augmenting search enters still has a shortest
  // path on to t, so it no longer wanders into the many corridor nodes that lead nowhere
  // (session 11, speed11: the forward labels made it scan about as many arcs as the search).
  bool label_distances_to(int t, int s) {
    std::fill(level_.begin(), level_.end(), -1);
    queue_.clear();
    queue_.push_back(t);
    level_[t] = 0;
    for (std::size_t q = 0; q < queue_.size(); ++q) {
      const int v = queue_[q];
      const int next = level_[v] + 1;
      for (int a = first_[v]; a < first_[v + 1]; ++a) {
        const Arc& arc = arcs_[a];
        // arc.back > 0: the arc arc.to -> v has residual capacity.
        if (arc.back > 0 && level_[arc.to] < 0) {
          level_[arc.to] = next;
          // Every node on a shortest s-t path is labelled by now: the augmenting search only
          // follows arcs one level down, so nodes found later are never on its paths.
          if (arc.to == s) return true;
          queue_.push_back(arc.to);
        }
      }
    }
    return false;
  }
  // Pushes up to `limit` from v towards t along arcs one level down and returns what it pushed.
  // A node keeps sending down its next arcs until its limit is used up, so one call from s finds
  // a whole blocking flow instead of re-descending from s for every path (session 11, speed11).
  long long dfs(int v, int t, long long limit) {
    if (v == t) return limit;
    long long pushed = 0;
    for (int& a = it_[v]; a < first_[v + 1]; ++a) {
      Arc& arc = arcs_[a];
      if (arc.cap <= 0 || level_[arc.to] != level_[v] - 1) continue;
      const long long f = dfs(arc.to, t, std::min(limit - pushed, arc.cap));
      if (f > 0) {
        arc.cap -= f;
        arc.back += f;
        Arc& reverse = arcs_[arc.rev];
        reverse.cap += f;
        reverse.back -= f;
        pushed += f;
        // Keep the arc current: it (or what lies behind it) may still carry more.
        if (pushed == limit) return pushed;
      }
    }
    return pushed;
  }

  std::vector<Pending> pending_;
  std::vector<int> first_;
  std::vector<Arc> arcs_;
  std::vector<int> level_, it_, queue_;
};

// At most this many vertices per corridor side: keeps each max flow cheap on huge graphs and
// bounds the depth of Dinic's recursive augmenting-path search (<= network size).
constexpr std::size_t kMaxCorridorVertices = 4000;

// Grows a BFS corridor inside block `own` from its vertices adjacent to block `other`, up to
// total weight `budget` and kMaxCorridorVertices vertices.
std::vector<int> corridor(const WorkGraph& g, const std::vector<int>& part, int own, int other,
                          long long budget, const std::vector<int>& boundary, std::vector<char>& in,
                          Rng& rng) {
  std::vector<int> region;
  if (budget <= 0) return region;
  std::vector<int> seeds;
  for (int v : boundary) {
    if (part[v] != own) continue;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e)
      if (part[g.adj[e]] == other) {
        seeds.push_back(v);
        break;
      }
  }
  for (int i = static_cast<int>(seeds.size()) - 1; i > 0; --i)
    std::swap(seeds[i], seeds[rng.below(i + 1)]);
  long long weight = 0;
  for (int v : seeds) {
    if (weight + g.vw[v] > budget || region.size() >= kMaxCorridorVertices) continue;
    in[v] = 1;
    region.push_back(v);
    weight += g.vw[v];
  }
  for (std::size_t q = 0; q < region.size(); ++q) {
    const int v = region[q];
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (in[u] || part[u] != own || weight + g.vw[u] > budget) continue;
      if (region.size() >= kMaxCorridorVertices) break;
      in[u] = 1;
      region.push_back(u);
      weight += g.vw[u];
    }
  }
  return region;
}

// One flow step on blocks a, b with corridors sized by `factor`. Returns the cut gain applied
// (0 when nothing better and balanced was found); `feasible_found` tells whether a balanced
// min cut existed at all (if not, a smaller corridor may help).
long long refine_pair(const WorkGraph& g, std::vector<int>& part, std::vector<long long>& bw,
                      const std::vector<long long>& ub, int a, int b,
                      const std::vector<int>& boundary, long long slack, double factor,
                      std::vector<char>& in, std::vector<int>& local, FlowNetwork& net, Rng& rng,
                      bool* feasible_found) {
  *feasible_found = false;
  if (boundary.empty()) return 0;
  const long long budget_a = std::max<long long>(0, ub[b] - bw[b]) +
                             static_cast<long long>(factor * static_cast<double>(slack));
  const long long budget_b = std::max<long long>(0, ub[a] - bw[a]) +
                             static_cast<long long>(factor * static_cast<double>(slack));
  std::vector<int> ra = corridor(g, part, a, b, budget_a, boundary, in, rng);
  std::vector<int> rb = corridor(g, part, b, a, budget_b, boundary, in, rng);
  std::vector<int> nodes = ra;
  nodes.insert(nodes.end(), rb.begin(), rb.end());
  const int m = static_cast<int>(nodes.size());
  const int s = m, t = m + 1;
  for (int i = 0; i < m; ++i) local[nodes[i]] = i;
  net.reset(m + 2);
  long long old_cut = 0;  // the current a-b cut as seen by this network
  for (int i = 0; i < m; ++i) {
    const int v = nodes[i];
    long long to_s = 0, to_t = 0;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (in[u]) {
        if (local[u] > i) net.add(i, local[u], g.ew[e], g.ew[e]);
        if (part[v] == a && part[u] == b) old_cut += g.ew[e];
      } else if (part[u] == a) {
        to_s += g.ew[e];
      } else if (part[u] == b) {
        to_t += g.ew[e];
      }
    }
    old_cut += part[v] == a ? to_t : to_s;
    if (to_s > 0) net.add(s, i, to_s, 0);
    if (to_t > 0) net.add(i, t, to_t, 0);
  }
  const long long new_cut = net.max_flow(s, t);
  long long gain = 0;
  if (new_cut <= old_cut) {
    // The two extreme minimum cuts: the smallest source side (reachable from s in the residual
    // network) and the largest (everything that cannot reach t). Of the balanced ones take the
    // better balanced. (Choosing the most balanced among all minimum cuts, via the residual
    // components, was tried and gave worse partitions on the benchmarks.)
    const std::vector<char> from_s = net.reachable_from(s);
    const std::vector<char> to_t = net.reaching(t);
    long long base_a = bw[a];
    for (int v : ra) base_a -= g.vw[v];
    const long long total = bw[a] + bw[b];
    long long best_max = LLONG_MAX, best_wa = 0;
    int best_option = -1;
    for (int option = 0; option < 2; ++option) {
      long long wa = base_a;
      for (int i = 0; i < m; ++i)
        if (option == 0 ? from_s[i] != 0 : to_t[i] == 0) wa += g.vw[nodes[i]];
      const long long wb = total - wa;
      if (wa > ub[a] || wb > ub[b]) continue;
      if (std::max(wa, wb) < best_max) {
        best_max = std::max(wa, wb);
        best_option = option;
        best_wa = wa;
      }
    }
    *feasible_found = best_option >= 0;
    if (*feasible_found && (new_cut < old_cut || best_max < std::max(bw[a], bw[b]))) {
      for (int i = 0; i < m; ++i) {
        const bool side_a = best_option == 0 ? from_s[i] != 0 : to_t[i] == 0;
        part[nodes[i]] = side_a ? a : b;
      }
      bw[a] = best_wa;
      bw[b] = total - best_wa;
      gain = old_cut - new_cut;
    }
  }
  for (int v : nodes) {
    in[v] = 0;
    local[v] = -1;
  }
  return gain;
}

}  // namespace

long long flow_refine(const WorkGraph& g, int k, std::vector<int>& part,
                      const std::vector<long long>& ub, const FlowParams& params, Rng& rng,
                      long long known_cut) {
  std::vector<long long> bw = block_weights(g, part, k);
  long long cut = known_cut >= 0 ? known_cut : edge_cut(g, part);
  if (k < 2) return cut;
  const long long avg = (g.total_vw + k - 1) / k;
  long long slack = 1;
  for (int b = 0; b < k; ++b) slack = std::max(slack, ub[b] - avg);
  std::vector<char> in(static_cast<std::size_t>(g.n), 0);
  std::vector<int> local(static_cast<std::size_t>(g.n), -1);
  FlowNetwork net;
  for (int round = 0; round < params.rounds; ++round) {
    // Boundary vertices of every adjacent block pair (a < b), collected once per round; later
    // pairs may see slightly stale lists, which only affects where their corridors start.
    std::map<std::pair<int, int>, std::vector<int>> boundary;
    std::vector<int> seen(static_cast<std::size_t>(k), -1);
    for (int v = 0; v < g.n; ++v)
      for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
        const int pu = part[g.adj[e]];
        if (pu == part[v] || seen[pu] == v) continue;
        seen[pu] = v;
        boundary[{std::min(pu, part[v]), std::max(pu, part[v])}].push_back(v);
      }
    std::vector<std::pair<int, int>> order;
    for (const auto& entry : boundary) order.push_back(entry.first);
    for (int i = static_cast<int>(order.size()) - 1; i > 0; --i)
      std::swap(order[i], order[rng.below(i + 1)]);
    long long round_gain = 0;
    for (const auto& ab : order) {
      for (double factor : {params.alpha, params.alpha / 4, 0.0}) {
        bool feasible = false;
        const long long gain = refine_pair(g, part, bw, ub, ab.first, ab.second, boundary[ab],
                                           slack, factor, in, local, net, rng, &feasible);
        round_gain += gain;
        if (feasible) break;  // a balanced min cut was found (applied if it helped)
      }
    }
    cut -= round_gain;
    if (round_gain == 0) break;
  }
  return cut;  // exact: every applied step gained exactly old_cut - flow on its network
}

}  // namespace tessera::partition_detail
