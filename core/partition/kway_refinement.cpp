#include "partition/kway_refinement.hpp"

#include <algorithm>
#include <climits>

#include "partition/block_connectivity.hpp"
#include "partition/gain_queue.hpp"

namespace tessera::partition_detail {
namespace {

struct Move {
  int target = -1;
  long long gain = LLONG_MIN;
};

// Whether v (its connectivity in c) may move to block b: no neighbour of v may then sit in a
// block that is forbidden next to b.
bool allowed(const BlockConnectivity& c, int b, int k, const ForbiddenPairs* forbidden) {
  if (!forbidden) return true;
  for (int q : c.touched)
    if (q != b && (*forbidden)[static_cast<std::size_t>(b) * k + q]) return false;
  return true;
}

// Best feasible move of v among the blocks it has neighbours in (ties: the lighter block).
Move best_adjacent_move(const WorkGraph& g, const std::vector<int>& part,
                        const std::vector<long long>& bw, const std::vector<long long>& ub,
                        BlockConnectivity& c, int v, const ForbiddenPairs* forbidden = nullptr) {
  c.compute(g, part, v);
  const int own = part[v];
  const long long internal = c.conn[own];
  const int k = static_cast<int>(bw.size());
  Move best;
  for (int b : c.touched) {
    if (b == own || bw[b] + g.vw[v] > ub[b] || !allowed(c, b, k, forbidden)) continue;
    const long long gain = c.conn[b] - internal;
    if (gain > best.gain || (gain == best.gain && bw[b] < bw[best.target])) best = {b, gain};
  }
  return best;
}

// Heap key: the gain, with random low bits so equal gains are taken in random order.
long long key_of(long long gain, Rng& rng) {
  return gain * 1024 + static_cast<long long>(rng.next() & 1023);
}

// FM searches on one partition: a search starts from a set of seed vertices, moves the best
// unlocked vertex again and again (negative gains allowed), queues the neighbours of moved
// vertices, stops after `stop_after` moves without a new best and rolls back to the best point.
class FmEngine {
 public:
  FmEngine(const WorkGraph& g, int k, std::vector<int>& part, const std::vector<long long>& ub,
           const ForbiddenPairs* forbidden)
      : g_(g),
        part_(part),
        ub_(ub),
        forbidden_(forbidden),
        bw_(block_weights(g, part, k)),
        conn_(k),
        queue_(g.n),
        lock_(static_cast<std::size_t>(g.n), 0) {
    if (k == 2 && !forbidden) init_two_way();
  }

  bool boundary(int v) const {
    if (two_way_) return external_[v] > 0;
    for (int e = g_.xadj[v]; e < g_.xadj[v + 1]; ++e)
      if (part_[g_.adj[e]] != part_[v]) return true;
    return false;
  }

  /// Returns the cut reduction (>= 0) kept after the rollback.
  long long search(const std::vector<int>& seeds, int stop_after, Rng& rng) {
    ++stamp_;
    moves_.clear();
    for (int v : seeds) {
      if (lock_[v] == stamp_) continue;
      const Move m = best_move(v);
      if (m.target >= 0) queue_.set(v, key_of(m.gain, rng));
    }
    long long delta = 0, best_delta = 0;
    long long best_max = *std::max_element(bw_.begin(), bw_.end());  // tie breaker at equal cut
    std::size_t best_len = 0;
    int since_best = 0;
    while (!queue_.empty()) {
      const long long key = queue_.top_key();
      const int v = queue_.pop();
      const Move m = best_move(v);
      if (m.target < 0) continue;
      if (m.gain * 1024 + 1023 < key) {  // block weights changed since v was queued
        queue_.set(v, key_of(m.gain, rng));
        continue;
      }
      const int from = part_[v];
      apply_move(v, m.target);
      lock_[v] = stamp_;
      moves_.emplace_back(v, from);
      delta -= m.gain;
      bool better = delta < best_delta;
      if (!better && delta == best_delta)  // same cut: keep it if it is better balanced
        better = *std::max_element(bw_.begin(), bw_.end()) < best_max;
      if (better) {
        best_delta = delta;
        best_max = *std::max_element(bw_.begin(), bw_.end());
        best_len = moves_.size();
        since_best = 0;
      } else if (++since_best > stop_after) {
        break;
      }
      for (int e = g_.xadj[v]; e < g_.xadj[v + 1]; ++e) {
        const int u = g_.adj[e];
        if (lock_[u] == stamp_) continue;
        const Move mu = best_move(u);
        if (mu.target >= 0)
          queue_.set(u, key_of(mu.gain, rng));
        else
          queue_.remove(u);
      }
    }
    queue_.clear();
    while (moves_.size() > best_len) {
      const auto [v, from] = moves_.back();
      moves_.pop_back();
      apply_move(v, from);
    }
    return -best_delta;
  }

  /// Vertices moved (and kept) by the last search.
  const std::vector<std::pair<int, int>>& kept_moves() const { return moves_; }

 private:
  // Bisections (k = 2) run FM thousands of times per initial partitioning. There each vertex's
  // weight towards the other block is kept up to date as vertices move, so a move's gain costs
  // O(1) instead of a scan of the neighbours. Same moves, same order, same result as the scan.
  void init_two_way() {
    weighted_degree_.assign(static_cast<std::size_t>(g_.n), 0);
    external_.assign(static_cast<std::size_t>(g_.n), 0);
    for (int v = 0; v < g_.n; ++v)
      for (int e = g_.xadj[v]; e < g_.xadj[v + 1]; ++e) {
        if (g_.ew[e] <= 0) return;  // the scan treats zero weights differently: keep it
        weighted_degree_[v] += g_.ew[e];
        if (part_[g_.adj[e]] != part_[v]) external_[v] += g_.ew[e];
      }
    two_way_ = true;
  }

  Move best_move(int v) {
    if (!two_way_) return best_adjacent_move(g_, part_, bw_, ub_, conn_, v, forbidden_);
    const int other = 1 - part_[v];
    if (external_[v] == 0 || bw_[other] + g_.vw[v] > ub_[other]) return {};
    return {other, 2 * external_[v] - weighted_degree_[v]};
  }

  void apply_move(int v, int to) {
    const int from = part_[v];
    part_[v] = to;
    bw_[from] -= g_.vw[v];
    bw_[to] += g_.vw[v];
    if (!two_way_) return;
    external_[v] = weighted_degree_[v] - external_[v];
    for (int e = g_.xadj[v]; e < g_.xadj[v + 1]; ++e)
      external_[g_.adj[e]] += part_[g_.adj[e]] == to ? -g_.ew[e] : g_.ew[e];
  }

  const WorkGraph& g_;
  std::vector<int>& part_;
  const std::vector<long long>& ub_;
  const ForbiddenPairs* forbidden_;
  std::vector<long long> bw_;
  BlockConnectivity conn_;
  GainQueue queue_;
  std::vector<int> lock_;
  int stamp_ = 0;
  std::vector<std::pair<int, int>> moves_;  // (vertex, block it came from)
  bool two_way_ = false;
  std::vector<long long> weighted_degree_, external_;  // k = 2 only
};

}  // namespace

long long kway_fm(const WorkGraph& g, int k, std::vector<int>& part,
                  const std::vector<long long>& ub, const FmParams& params, Rng& rng,
                  long long known_cut, const ForbiddenPairs* forbidden) {
  long long cut = known_cut >= 0 ? known_cut : edge_cut(g, part);
  if (k < 2) return cut;
  FmEngine fm(g, k, part, ub, forbidden);
  for (int pass = 0; pass < params.max_passes; ++pass) {
    std::vector<int> seeds;
    for (int v : random_order(g.n, rng))
      if (fm.boundary(v)) seeds.push_back(v);
    const long long gain = fm.search(seeds, params.stop_after, rng);
    cut -= gain;
    if (gain == 0) break;
  }
  for (int round = 0; round < params.local_rounds; ++round) {
    // Localized searches from single boundary vertices find improvements a global pass misses
    // because its queue is dominated by the best gains elsewhere.
    long long round_gain = 0;
    std::vector<char> used(static_cast<std::size_t>(g.n), 0);
    std::vector<int> seed(1);
    for (int v : random_order(g.n, rng)) {
      if (used[v] || !fm.boundary(v)) continue;
      seed[0] = v;
      used[v] = 1;
      const long long gain = fm.search(seed, params.local_stop_after, rng);
      for (const auto& mv : fm.kept_moves()) used[mv.first] = 1;
      round_gain += gain;
    }
    cut -= round_gain;
    if (round_gain == 0) break;
  }
  return cut;
}

bool rebalance(const WorkGraph& g, int k, std::vector<int>& part, const std::vector<long long>& ub,
               const ForbiddenPairs* forbidden) {
  std::vector<long long> bw = block_weights(g, part, k);
  auto overloaded = [&](int b) { return bw[b] > ub[b]; };
  bool any = false;
  for (int b = 0; b < k; ++b) any = any || overloaded(b);
  if (!any) return true;
  BlockConnectivity c(k);
  // Best move of v anywhere: an adjacent block with room, or else the block with most room.
  auto best_move = [&](int v) {
    Move m = best_adjacent_move(g, part, bw, ub, c, v, forbidden);
    int roomiest = -1;
    for (int b = 0; b < k; ++b)
      if (b != part[v] && bw[b] + g.vw[v] <= ub[b] && allowed(c, b, k, forbidden) &&
          (roomiest < 0 || ub[b] - bw[b] > ub[roomiest] - bw[roomiest]))
        roomiest = b;
    if (roomiest >= 0) {
      const long long gain = c.conn[roomiest] - c.conn[part[v]];
      if (gain > m.gain) m = {roomiest, gain};
    }
    return m;
  };
  GainQueue queue(g.n);
  std::vector<char> moved(static_cast<std::size_t>(g.n), 0);
  for (int v = 0; v < g.n; ++v) {
    if (!overloaded(part[v])) continue;
    const Move m = best_move(v);
    // Lighter vertices first among equal gains: they overshoot less on coarse levels.
    if (m.target >= 0) queue.set(v, m.gain * 4096 - std::min(g.vw[v], 4095));
  }
  while (!queue.empty()) {
    const int v = queue.pop();
    if (!overloaded(part[v])) continue;
    const Move m = best_move(v);
    if (m.target < 0) continue;
    const int from = part[v];
    part[v] = m.target;
    bw[from] -= g.vw[v];
    bw[m.target] += g.vw[v];
    moved[v] = 1;
    for (int e = g.xadj[v]; e < g.xadj[v + 1]; ++e) {
      const int u = g.adj[e];
      if (moved[u] || !overloaded(part[u])) continue;
      const Move mu = best_move(u);
      if (mu.target >= 0) queue.set(u, mu.gain * 4096 - std::min(g.vw[u], 4095));
    }
  }
  for (int b = 0; b < k; ++b)
    if (overloaded(b)) return false;
  return true;
}

}  // namespace tessera::partition_detail
