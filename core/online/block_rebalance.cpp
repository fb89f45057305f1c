#include <algorithm>
#include <cmath>
#include <set>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

namespace tessera {

void RebalanceOptions::validate() const {
  if (!(slack >= 0) || !std::isfinite(slack))
    throw InputError("RebalanceOptions.slack must be a finite number >= 0");
}

RebalanceResult rebalance_blocks(const PoseGraph& graph, std::vector<int>& owner, int num_blocks,
                                 const RebalanceOptions& options) {
  options.validate();
  RebalanceResult res;
  const std::size_t n = graph.num_poses;
  if (owner.size() != n || num_blocks <= 0) return res;
  std::vector<std::size_t> size(static_cast<std::size_t>(num_blocks), 0);
  for (int b : owner) ++size[static_cast<std::size_t>(b)];
  res.largest_before = *std::max_element(size.begin(), size.end());
  res.largest_after = res.largest_before;
  if (!options.enabled || num_blocks == 1) return res;
  const double bound =
      (1.0 + options.slack) * std::ceil(static_cast<double>(n) / static_cast<double>(num_blocks));
  auto over = [&](std::size_t s) {
    return static_cast<double>(s) > bound + static_cast<double>(options.min_excess);
  };
  // Nothing over the bound (most steps): done before the graph's adjacency is built.
  if (std::none_of(size.begin(), size.end(), over)) return res;
  std::vector<std::vector<std::size_t>> adjacent(n);
  for (const Measurement& m : graph.measurements) {
    adjacent[m.i].push_back(m.j);
    adjacent[m.j].push_back(m.i);
  }
  const std::size_t blocks = static_cast<std::size_t>(num_blocks);
  // Per pose, its measurements into each block (few blocks a pose: a short list); per pair of
  // blocks (b, c), the poses of b that may move and have a measurement into c, in id order.
  // Kept up to date move by move, so a move costs the moved pose's degree, not a scan of the
  // graph (which made a call that moves M poses O(M n)).
  std::vector<std::vector<std::pair<int, std::size_t>>> into(n);
  std::vector<std::set<std::size_t>> border(blocks * blocks);
  auto count = [&](std::size_t q, int c) -> std::size_t& {
    for (auto& e : into[q])
      if (e.first == c) return e.second;
    into[q].emplace_back(c, 0);
    return into[q].back().second;
  };
  std::vector<char> moved(n, 0);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t q : adjacent[k]) ++count(k, owner[q]);
  for (std::size_t k = 0; k < n; ++k)
    for (const auto& [c, links] : into[k])
      if (c != owner[k] && links > 0)
        border[static_cast<std::size_t>(owner[k]) * blocks + static_cast<std::size_t>(c)].insert(k);
  // Each pass moves one pose out of the largest over-full block that has a lighter neighbour
  // block: the lowest-id pose among those with a measurement into the lightest block at least
  // two poses lighter, to the first such block among its measurements. A pose moves at most
  // once per call, so the loop ends.
  std::vector<int> order(blocks);
  for (;;) {
    for (int b = 0; b < num_blocks; ++b) order[static_cast<std::size_t>(b)] = b;
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return size[static_cast<std::size_t>(a)] > size[static_cast<std::size_t>(b)];
    });
    bool any = false;
    for (int big : order) {
      const std::size_t bg = static_cast<std::size_t>(big);
      const std::size_t big_size = size[bg];
      if (!over(big_size) || big_size <= 1) break;  // the rest are smaller
      std::size_t lightest = 0, best_pose = n;
      for (std::size_t c = 0; c < blocks; ++c) {
        const std::set<std::size_t>& cand = border[bg * blocks + c];
        if (c == bg || cand.empty() || size[c] + 2 > big_size) continue;
        if (best_pose == n || size[c] < lightest) {
          lightest = size[c];
          best_pose = *cand.begin();
        } else if (size[c] == lightest) {
          best_pose = std::min(best_pose, *cand.begin());
        }
      }
      if (best_pose == n) continue;  // no lighter neighbour: try the next block
      int best_block = -1;
      for (std::size_t q : adjacent[best_pose]) {
        const int c = owner[q];
        if (c != big && size[static_cast<std::size_t>(c)] == lightest) {
          best_block = c;
          break;
        }
      }
      // The moved pose leaves every candidate list; its neighbours' links follow it.
      for (const auto& [c, links] : into[best_pose])
        if (c != big && links > 0)
          border[bg * blocks + static_cast<std::size_t>(c)].erase(best_pose);
      owner[best_pose] = best_block;
      moved[best_pose] = 1;
      for (std::size_t q : adjacent[best_pose]) {
        const std::size_t b = static_cast<std::size_t>(owner[q]);
        if (--count(q, big) == 0 && b != bg) border[b * blocks + bg].erase(q);
        if (++count(q, best_block) == 1 && b != static_cast<std::size_t>(best_block) && !moved[q])
          border[b * blocks + static_cast<std::size_t>(best_block)].insert(q);
      }
      --size[bg];
      ++size[static_cast<std::size_t>(best_block)];
      ++res.moved;
      any = true;
      break;
    }
    if (!any) break;
  }
  res.largest_after = *std::max_element(size.begin(), size.end());
  return res;
}

}  // namespace tessera
