#include "partition/quotient_colouring.hpp"

#include <algorithm>
#include <numeric>

#include "partition/block_connectivity.hpp"

namespace tessera::partition_detail {
namespace {

// Branch and bound over the blocks in order of falling degree: each block takes a colour already
// used or one new colour, and a branch stops once it needs as many colours as the best found.
// Quotient graphs have at most 64 vertices and are sparse for pose graphs, so this ends fast;
// the node budget bounds the dense cases.
class MinColouring {
 public:
  MinColouring(const std::vector<char>& adj, int k, long long budget)
      : adj_(adj), k_(k), budget_(budget), colour_(static_cast<std::size_t>(k), -1) {
    order_.resize(static_cast<std::size_t>(k));
    std::iota(order_.begin(), order_.end(), 0);
    std::vector<int> degree(static_cast<std::size_t>(k), 0);
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b) degree[a] += adj_[static_cast<std::size_t>(a) * k + b];
    std::stable_sort(order_.begin(), order_.end(),
                     [&](int a, int b) { return degree[a] > degree[b]; });
    // Greedy in that order gives the first bound.
    best_ = k + 1;
    greedy();
  }

  void run() { branch(0, 0); }
  int colours() const { return best_; }
  const std::vector<int>& colouring() const { return best_colour_; }

 private:
  bool conflict(int v, int c) const {
    for (int u = 0; u < k_; ++u)
      if (adj_[static_cast<std::size_t>(v) * k_ + u] && colour_[u] == c) return true;
    return false;
  }

  void greedy() {
    int used = 0;
    for (int v : order_) {
      int c = 0;
      while (conflict(v, c)) ++c;
      colour_[v] = c;
      used = std::max(used, c + 1);
    }
    best_ = used;
    best_colour_ = colour_;
    std::fill(colour_.begin(), colour_.end(), -1);
  }

  void branch(int depth, int used) {
    if (used >= best_ || budget_-- <= 0) return;
    if (depth == k_) {
      best_ = used;
      best_colour_ = colour_;
      return;
    }
    const int v = order_[static_cast<std::size_t>(depth)];
    for (int c = 0; c <= used && c < best_ - 1; ++c) {
      if (conflict(v, c)) continue;
      colour_[v] = c;
      branch(depth + 1, std::max(used, c + 1));
      colour_[v] = -1;
    }
  }

  const std::vector<char>& adj_;
  int k_;
  long long budget_;
  std::vector<int> order_, colour_, best_colour_;
  int best_ = 0;
};

// Moves every vertex that has a neighbour in a block forbidden next to its own into the block
// (allowed next to all of its neighbours' blocks) it is joined to most. A move removes the
// vertex's forbidden edges and adds none, so the forbidden weight falls with every move.
// Returns false when some vertex has no allowed block.
bool repair(const WorkGraph& g, int k, std::vector<int>& part, const ForbiddenPairs& forbidden,
            Rng& rng) {
  const std::vector<int> order = random_order(g.n, rng);
  std::vector<long long> bw = block_weights(g, part, k);
  BlockConnectivity t(k);
  auto forbidden_pair = [&](int a, int b) {
    return forbidden[static_cast<std::size_t>(a) * k + b] != 0;
  };
  for (int pass = 0; pass < 8; ++pass) {
    int violating = 0, moved = 0;
    for (int v : order) {
      t.compute(g, part, v);
      const int own = part[v];
      bool bad = false;
      for (int q : t.touched) bad = bad || (q != own && forbidden_pair(own, q));
      if (!bad) continue;
      ++violating;
      int target = -1;
      for (int b = 0; b < k; ++b) {
        if (b == own) continue;
        bool ok = true;
        for (int q : t.touched) ok = ok && (q == b || !forbidden_pair(b, q));
        if (!ok) continue;
        if (target < 0 || t.conn[b] > t.conn[target] ||
            (t.conn[b] == t.conn[target] && bw[b] < bw[target]))
          target = b;
      }
      if (target < 0) continue;
      part[v] = target;
      bw[own] -= g.vw[v];
      bw[target] += g.vw[v];
      ++moved;
    }
    if (violating == 0) return true;
    if (moved == 0) return false;
  }
  return false;
}

bool violates(const WorkGraph& g, const std::vector<int>& part, const ForbiddenPairs& forbidden,
              int k) {
  for (int v = 0; v < g.n; ++v)
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int a = part[v], b = part[g.adj[e]];
      if (a != b && forbidden[static_cast<std::size_t>(a) * k + b]) return true;
    }
  return false;
}

bool within(const WorkGraph& g, const std::vector<int>& part, const std::vector<long long>& ub,
            int k) {
  const std::vector<long long> bw = block_weights(g, part, k);
  for (int b = 0; b < k; ++b)
    if (bw[b] > ub[b] || bw[b] == 0) return false;  // every block keeps a vertex
  return true;
}

// Renumbers blocks by (colour, old id): blocks of colour 0 first. A greedy colouring in block-id
// order then uses at most as many colours as `colour` does.
void order_by_colour(std::vector<int>& part, const std::vector<int>& colour, int k) {
  std::vector<int> order(static_cast<std::size_t>(k));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return colour[a] < colour[b]; });
  std::vector<int> new_id(static_cast<std::size_t>(k));
  for (int i = 0; i < k; ++i) new_id[order[i]] = i;
  for (int& b : part) b = new_id[b];
}

}  // namespace

QuotientColouring colour_quotient(const WorkGraph& g, const std::vector<int>& part, int k,
                                  long long node_budget) {
  QuotientColouring q;
  q.k = k;
  q.weight.assign(static_cast<std::size_t>(k) * k, 0);
  for (int v = 0; v < g.n; ++v)
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int a = part[v], b = part[g.adj[e]];
      if (a != b) q.weight[static_cast<std::size_t>(a) * k + b] += g.ew[e];
    }
  std::vector<char> adj(q.weight.size(), 0);
  for (std::size_t i = 0; i < adj.size(); ++i) adj[i] = q.weight[i] > 0;
  for (int a = 0; a < k; ++a)
    for (int b = a + 1; b < k; ++b) q.adjacent_pairs += adj[static_cast<std::size_t>(a) * k + b];
  MinColouring mc(adj, k, node_budget);
  mc.run();
  q.colours = mc.colours();
  q.colour = mc.colouring();
  return q;
}

ColourPassResult colour_pass(const WorkGraph& g, int k, const std::vector<long long>& ub,
                             std::vector<int>& part, const ColourPassOptions& options, Rng& rng) {
  ColourPassResult result;
  QuotientColouring q = colour_quotient(g, part, k);
  result.cut_before = result.cut_after = edge_cut(g, part);
  result.colours_before = result.colours_after = q.colours;
  const long long limit = static_cast<long long>(static_cast<double>(result.cut_before) *
                                                 (1.0 + options.max_cut_increase));
  while (q.colours > std::max(2, options.min_colours)) {
    // Candidate merges: pairs of colour classes, the least joined (cut weight between them)
    // first, since those vertices have to move.
    std::vector<std::pair<long long, std::pair<int, int>>> pairs;
    for (int x = 0; x < q.colours; ++x)
      for (int y = x + 1; y < q.colours; ++y) {
        long long w = 0;
        for (int a = 0; a < k; ++a)
          for (int b = 0; b < k; ++b)
            if (q.colour[a] == x && q.colour[b] == y)
              w += q.weight[static_cast<std::size_t>(a) * k + b];
        pairs.push_back({w, {x, y}});
      }
    std::stable_sort(pairs.begin(), pairs.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<int> best;
    long long best_cut = -1;
    const int tries = std::min<int>(options.tries, static_cast<int>(pairs.size()));
    for (int i = 0; i < tries; ++i) {
      const auto [x, y] = pairs[static_cast<std::size_t>(i)].second;
      ForbiddenPairs forbidden(static_cast<std::size_t>(k) * k, 0);
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const int ca = q.colour[a] == y ? x : q.colour[a];
          const int cb = q.colour[b] == y ? x : q.colour[b];
          forbidden[static_cast<std::size_t>(a) * k + b] = a != b && ca == cb;
        }
      std::vector<int> trial = part;
      if (!repair(g, k, trial, forbidden, rng)) continue;
      rebalance(g, k, trial, ub, &forbidden);
      const long long cut = kway_fm(g, k, trial, ub, options.fm, rng, -1, &forbidden);
      if (!within(g, trial, ub, k) || violates(g, trial, forbidden, k)) continue;
      if (best_cut < 0 || cut < best_cut) {
        best_cut = cut;
        best.swap(trial);
      }
    }
    if (best_cut < 0 || best_cut > limit) break;
    part.swap(best);
    q = colour_quotient(g, part, k);
    result.cut_after = best_cut;
    result.colours_after = q.colours;
  }
  order_by_colour(part, q.colour, k);
  return result;
}

}  // namespace tessera::partition_detail
