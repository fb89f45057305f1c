#include <algorithm>
#include <cmath>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/util/input_error.hpp>

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
  // Each pass moves one pose out of the largest over-full block that has a lighter neighbour
  // block; a pose moves at most once per call, so the loop ends.
  std::vector<char> moved(n, 0);
  std::vector<int> order(static_cast<std::size_t>(num_blocks));
  for (;;) {
    for (int b = 0; b < num_blocks; ++b) order[static_cast<std::size_t>(b)] = b;
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return size[static_cast<std::size_t>(a)] > size[static_cast<std::size_t>(b)];
    });
    bool any = false;
    for (int big : order) {
      const std::size_t big_size = size[static_cast<std::size_t>(big)];
      if (!over(big_size) || big_size <= 1) break;  // the rest are smaller
      // The border pose whose lightest neighbouring block is lightest (lowest ids on ties).
      std::size_t best_pose = n;
      int best_block = -1;
      for (std::size_t k = 0; k < n; ++k) {
        if (owner[k] != big || moved[k]) continue;
        for (std::size_t q : adjacent[k]) {
          const int c = owner[q];
          if (c == big || size[static_cast<std::size_t>(c)] + 2 > big_size) continue;
          if (best_block < 0 ||
              size[static_cast<std::size_t>(c)] < size[static_cast<std::size_t>(best_block)]) {
            best_block = c;
            best_pose = k;
          }
        }
      }
      if (best_block < 0) continue;  // no lighter neighbour: try the next block
      owner[best_pose] = best_block;
      moved[best_pose] = 1;
      --size[static_cast<std::size_t>(big)];
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
