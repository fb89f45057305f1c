#pragma once
// Internal: an addressable max-priority queue of vertices keyed by move gain, used by the FM
// refinement, the rebalancer and greedy graph growing. Gains on coarse levels are weighted and
// spread widely, so a binary heap with a position index replaces the classic bucket array while
// giving the same operations (insert, change key, remove, pop max) in O(log n).

#include <utility>
#include <vector>

namespace tessera::partition_detail {

class GainQueue {
 public:
  explicit GainQueue(int n = 0) { reset(n); }
  void reset(int n) {
    pos_.assign(static_cast<std::size_t>(n), -1);
    heap_.clear();
  }
  /// Empties the queue in time proportional to its size (the index keeps its length).
  void clear() {
    for (const auto& entry : heap_) pos_[entry.second] = -1;
    heap_.clear();
  }
  bool empty() const { return heap_.empty(); }
  bool contains(int v) const { return pos_[v] >= 0; }
  long long top_key() const { return heap_[0].first; }
  int top() const { return heap_[0].second; }

  /// Inserts v or changes its key.
  void set(int v, long long key) {
    if (pos_[v] < 0) {
      pos_[v] = static_cast<int>(heap_.size());
      heap_.emplace_back(key, v);
      up(pos_[v]);
    } else {
      const int p = pos_[v];
      const long long old = heap_[p].first;
      heap_[p].first = key;
      if (key > old)
        up(p);
      else
        down(p);
    }
  }
  void remove(int v) {
    const int p = pos_[v];
    if (p < 0) return;
    pos_[v] = -1;
    const int last = static_cast<int>(heap_.size()) - 1;
    if (p != last) {
      heap_[p] = heap_[last];
      pos_[heap_[p].second] = p;
      heap_.pop_back();
      const int moved = heap_[p].second;
      up(p);
      down(pos_[moved]);
    } else {
      heap_.pop_back();
    }
  }
  int pop() {
    const int v = heap_[0].second;
    remove(v);
    return v;
  }

 private:
  void up(int p) {
    while (p > 0) {
      const int q = (p - 1) / 2;
      if (heap_[q].first >= heap_[p].first) break;
      swap_at(p, q);
      p = q;
    }
  }
  void down(int p) {
    const int size = static_cast<int>(heap_.size());
    for (;;) {
      int best = p;
      const int l = 2 * p + 1, r = l + 1;
      if (l < size && heap_[l].first > heap_[best].first) best = l;
      if (r < size && heap_[r].first > heap_[best].first) best = r;
      if (best == p) return;
      swap_at(p, best);
      p = best;
    }
  }
  void swap_at(int a, int b) {
    std::swap(heap_[a], heap_[b]);
    pos_[heap_[a].second] = a;
    pos_[heap_[b].second] = b;
  }

  std::vector<int> pos_;
  std::vector<std::pair<long long, int>> heap_;
};

}  // namespace tessera::partition_detail
