#include "partition/flow_refinement.hpp"

#include <algorithm>
#include <climits>
#include <map>
#include <utility>

namespace tessera::partition_detail {
namespace {

// Max flow on a small network, by Boykov and Kolmogorov's search-tree algorithm ("An
// experimental comparison of min-cut/max-flow algorithms for energy minimization in vision",
// 2004). Arcs are collected first and then laid out per node (CSR: a node's arcs are
// contiguous, each with the index of its reverse arc). Which maximum flow is found does not
// matter: the residual sets used below (what s reaches, what reaches t) are the same for every
// maximum flow, so every partition is bit-identical to the earlier Dinic code's. Dinic rebuilt
// its level graph with one scan of the network per phase (~22 % of a highest run on rim); the
// two search trees here (one from s, one into t) are kept between augmentations and only
// repaired where an augmentation saturated a tree arc.
class FlowNetwork {
 public:
  /// Empties the network and gives it n nodes; keeps the buffers' memory, since one network
  /// is rebuilt for every block pair and corridor size of a round.
  void reset(int n) {
    first_.assign(static_cast<std::size_t>(n) + 1, 0);
    pending_.clear();
  }
  /// Adds the arc pair u -> v (capacity c_uv) and v -> u (c_vu). Only before max_flow().
  void add(int u, int v, long long c_uv, long long c_vu) {
    pending_.push_back({u, v, c_uv, c_vu});
    ++first_[u + 1];
    ++first_[v + 1];
  }
  long long max_flow(int s, int t);
  /// Nodes reachable from s in the residual network, after max_flow(): the source tree. When
  /// no tree can grow, no residual arc leaves the source tree (its nodes scanned every arc out,
  /// and an augmentation only adds residual capacity within a tree or from the sink tree into
  /// the source tree), and every tree node is joined to its root by residual arcs.
  std::vector<char> reachable_from() const { return in_tree(kSource); }
  /// Nodes that can reach t in the residual network, after max_flow(): the sink tree.
  std::vector<char> reaching() const { return in_tree(kSink); }

 private:
  struct Pending {
    int u, v;
    long long c_uv, c_vu;
  };
  // One arc with everything the searches read together: one 24-byte record instead of parallel
  // arrays (fewer cache lines per scanned arc).
  //
  // `back` mirrors the reverse arc's capacity so that searches against the arc direction (the
  // tree into t, the set reaching t) stay within the record.
  struct Arc {
    int to, rev;
    long long cap, back;
  };
  enum : char { kFree = 0, kSource = 1, kSink = 2 };
  // parent_ markers besides an arc index (the arc from the node to its parent).
  static constexpr int kRoot = -1, kOrphan = -2;

  void build() {
    const std::size_t n = first_.size() - 1;
    for (std::size_t v = 0; v < n; ++v) first_[v + 1] += first_[v];
    arcs_.resize(2 * pending_.size());
    fill_.assign(first_.begin(), first_.end() - 1);
    for (const Pending& p : pending_) {
      const int a = fill_[p.u]++, b = fill_[p.v]++;
      arcs_[a] = {p.v, b, p.c_uv, p.c_vu};
      arcs_[b] = {p.u, a, p.c_vu, p.c_uv};
    }
    pending_.clear();
  }
  void push(int a, long long f) {
    Arc& arc = arcs_[a];
    arc.cap -= f;
    arc.back += f;
    Arc& reverse = arcs_[arc.rev];
    reverse.cap += f;
    reverse.back -= f;
  }
  void activate(int v) {
    if (!active_[v]) {
      active_[v] = 1;
      queue_.push_back(v);
    }
  }
  bool grow(int* meet);
  long long augment(int meet);
  void adopt(int v);
  std::vector<char> in_tree(char tree) const {
    std::vector<char> in(tree_.size());
    for (std::size_t v = 0; v < tree_.size(); ++v) in[v] = tree_[v] == tree;
    return in;
  }

  std::vector<Pending> pending_;
  std::vector<int> first_, fill_;
  std::vector<Arc> arcs_;
  // Search trees: which tree a node is in, the arc to its parent, and for the origin checks of
  // adoption the distance to the root and the augmentation (stamp) at which that was last known.
  std::vector<char> tree_, active_;
  std::vector<int> parent_, dist_, stamp_;
  std::vector<int> up_;  // the parent node (arcs_[parent_[v]].to), for the walks to the root
  std::vector<int> queue_, orphans_;
  std::size_t head_ = 0;
  int time_ = 0;
};

long long FlowNetwork::max_flow(int s, int t) {
  build();
  const std::size_t n = first_.size() - 1;
  tree_.assign(n, kFree);
  active_.assign(n, 0);
  parent_.assign(n, kOrphan);
  up_.assign(n, -1);
  dist_.assign(n, 0);
  stamp_.assign(n, 0);
  queue_.clear();
  orphans_.clear();
  head_ = 0;
  time_ = 0;
  tree_[s] = kSource;
  tree_[t] = kSink;
  parent_[s] = parent_[t] = kRoot;
  dist_[s] = dist_[t] = 1;  // as the origin checks count them
  activate(s);
  activate(t);
  long long flow = 0;
  int meet = -1;
  while (grow(&meet)) {
    ++time_;
    flow += augment(meet);
    // Adopt in FIFO order; adopt() may append more orphans.
    for (std::size_t i = 0; i < orphans_.size(); ++i) adopt(orphans_[i]);
    orphans_.clear();
  }
  return flow;
}

// Grows both trees from the active nodes until they touch. Returns true with *meet = an arc
// from a source-tree node to a sink-tree node with residual capacity, false when no s-t path is
// left (the flow is maximum).
bool FlowNetwork::grow(int* meet) {
  // Raw pointers in locals: stores through the char arrays may alias any member, so the
  // compiler would reload every vector's data pointer per arc otherwise (~1/3 of this loop).
  const int* first = first_.data();
  const Arc* arcs = arcs_.data();
  char* tree = tree_.data();
  char* active = active_.data();
  int* parent = parent_.data();
  int* up = up_.data();
  int* dist = dist_.data();
  int* stamp = stamp_.data();
  while (head_ < queue_.size()) {
    const int p = queue_[head_];
    const char tp = tree[p];
    if (tp == kFree) {  // freed by an adoption since it was queued
      active[p] = 0;
      ++head_;
      continue;
    }
    const bool source = tp == kSource;
    for (int a = first[p], end = first[p + 1]; a < end; ++a) {
      const Arc& arc = arcs[a];
      // Residual capacity outwards from the source tree, inwards into the sink tree.
      if ((source ? arc.cap : arc.back) <= 0) continue;
      const int q = arc.to;
      if (tree[q] == kFree) {
        tree[q] = tp;
        parent[q] = arc.rev;
        up[q] = p;
        dist[q] = dist[p] + 1;
        stamp[q] = stamp[p];
        if (!active[q]) {
          active[q] = 1;
          queue_.push_back(q);
        }
      } else if (tree[q] != tp) {
        *meet = source ? a : arc.rev;  // p stays active: it may have more to give
        return true;
      } else if (stamp[q] <= stamp[p] && dist[q] > dist[p]) {
        // Shorter way to the root (the BK heuristic that keeps the trees shallow).
        parent[q] = arc.rev;
        up[q] = p;
        dist[q] = dist[p] + 1;
        stamp[q] = stamp[p];
      }
    }
    active[p] = 0;
    ++head_;
  }
  return false;
}

// Pushes the bottleneck along root -> ... -> meet -> ... -> root and turns nodes whose tree arc
// it saturated into orphans.
long long FlowNetwork::augment(int meet) {
  long long f = arcs_[meet].cap;
  const int u = arcs_[arcs_[meet].rev].to, w = arcs_[meet].to;
  for (int v = u; parent_[v] != kRoot; v = arcs_[parent_[v]].to)
    f = std::min(f, arcs_[parent_[v]].back);
  for (int v = w; parent_[v] != kRoot; v = arcs_[parent_[v]].to)
    f = std::min(f, arcs_[parent_[v]].cap);
  push(meet, f);
  for (int v = u; parent_[v] != kRoot;) {
    const int a = parent_[v], up = arcs_[a].to;
    push(arcs_[a].rev, f);
    if (arcs_[a].back == 0) {
      parent_[v] = kOrphan;
      orphans_.push_back(v);
    }
    v = up;
  }
  for (int v = w; parent_[v] != kRoot;) {
    const int a = parent_[v], up = arcs_[a].to;
    push(a, f);
    if (arcs_[a].cap == 0) {
      parent_[v] = kOrphan;
      orphans_.push_back(v);
    }
    v = up;
  }
  return f;
}

// Finds an orphan a new parent in its tree whose path leads to the root (the one nearest the
// root), or else frees it: its children become orphans and its tree neighbours that could grow
// into it again become active.
void FlowNetwork::adopt(int v) {
  // Raw pointers in locals, as in grow().
  const int* first = first_.data();
  const Arc* arcs = arcs_.data();
  char* tree_of = tree_.data();
  int* parent = parent_.data();
  int* up = up_.data();
  int* dist = dist_.data();
  int* stamp = stamp_.data();
  const int now = time_;
  const char tree = tree_of[v];
  int best = -1, best_dist = INT_MAX;
  for (int a = first[v]; a < first[v + 1]; ++a) {
    const Arc& arc = arcs[a];
    const int q = arc.to;
    if (tree_of[q] != tree || (tree == kSource ? arc.back : arc.cap) <= 0) continue;
    // Origin check: walk up from q until the root, a node already checked in this
    // augmentation, or an orphan.
    int d = 0, j = q;
    bool rooted = false;
    while (true) {
      if (stamp[j] == now) {
        d += dist[j];
        rooted = true;
        break;
      }
      const int pa = parent[j];
      ++d;
      if (pa == kRoot) {
        stamp[j] = now;
        dist[j] = 1;
        rooted = true;
        break;
      }
      if (pa == kOrphan) break;
      j = up[j];
    }
    if (!rooted) continue;
    if (d < best_dist) {
      best = a;
      best_dist = d;
    }
    // Remember the distances on the path for the next checks.
    for (j = q; stamp[j] != now; j = up[j]) {
      stamp[j] = now;
      dist[j] = d--;
    }
  }
  if (best >= 0) {
    parent[v] = best;
    up[v] = arcs[best].to;
    stamp[v] = now;
    dist[v] = best_dist + 1;
    return;
  }
  for (int a = first[v]; a < first[v + 1]; ++a) {
    const Arc& arc = arcs[a];
    const int q = arc.to;
    if (tree_of[q] != tree) continue;
    if ((tree == kSource ? arc.back : arc.cap) > 0) activate(q);
    if (parent[q] >= 0 && up[q] == v) {
      parent[q] = kOrphan;
      orphans_.push_back(q);
    }
  }
  tree_of[v] = kFree;
}

// At most this many vertices per corridor side: keeps each max flow cheap on huge graphs.
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
  // Raw pointers in locals: the stores into `in` (chars) may alias anything, so the vectors'
  // data pointers would be reloaded per scanned edge otherwise.
  const int* xadj = g.xadj.data();
  const int* adj = g.adj.data();
  const int* vw = g.vw.data();
  const int* block = part.data();
  char* inside = in.data();
  for (std::size_t q = 0; q < region.size(); ++q) {
    const int v = region[q];
    for (int e = xadj[v], end = xadj[v + 1]; e < end; ++e) {
      const int u = adj[e];
      if (inside[u] || block[u] != own || weight + vw[u] > budget) continue;
      if (region.size() >= kMaxCorridorVertices) break;
      inside[u] = 1;
      region.push_back(u);
      weight += vw[u];
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
  const int* xadj = g.xadj.data();
  const int* adj = g.adj.data();
  const int* ew = g.ew.data();
  const int* block = part.data();
  const int* index = local.data();  // >= 0 exactly for the corridor nodes (`in` set)
  for (int i = 0; i < m; ++i) {
    const int v = nodes[i];
    const bool side_a = block[v] == a;
    long long to_s = 0, to_t = 0;
    for (int e = xadj[v], end = xadj[v + 1]; e < end; ++e) {
      const int u = adj[e];
      const int j = index[u];
      if (j >= 0) {
        if (j > i) net.add(i, j, ew[e], ew[e]);
        if (side_a && block[u] == b) old_cut += ew[e];
      } else if (block[u] == a) {
        to_s += ew[e];
      } else if (block[u] == b) {
        to_t += ew[e];
      }
    }
    old_cut += side_a ? to_t : to_s;
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
    const std::vector<char> from_s = net.reachable_from();
    const std::vector<char> to_t = net.reaching();
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
