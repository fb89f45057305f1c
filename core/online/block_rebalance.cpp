#include <algorithm>
#include <cmath>
#include <queue>
#include <set>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/util/input_error.hpp>
#include <tuple>
#include <utility>

namespace tessera {

void RebalanceOptions::validate() const {
  if (!(slack >= 0) || !std::isfinite(slack))
    throw InputError("RebalanceOptions.slack must be a finite number >= 0");
  if (!(cut_fraction >= 0 && cut_fraction <= 1))
    throw InputError("RebalanceOptions.cut_fraction must be in [0, 1] (1 = no cut refinement)");
  if (max_passes < 1) throw InputError("RebalanceOptions.max_passes must be >= 1");
  if (pass_patience < 1) throw InputError("RebalanceOptions.pass_patience must be >= 1");
}

namespace {

std::vector<std::vector<std::size_t>> adjacency(const PoseGraph& graph) {
  std::vector<std::vector<std::size_t>> adjacent(graph.num_poses);
  for (const Measurement& m : graph.measurements) {
    adjacent[m.i].push_back(m.j);
    adjacent[m.j].push_back(m.i);
  }
  return adjacent;
}

// Per pose, its measurements into each block (few blocks a pose: a short list).
class BlockLinks {
 public:
  BlockLinks(const std::vector<std::vector<std::size_t>>& adjacent, const std::vector<int>& owner)
      : into_(adjacent.size()) {
    for (std::size_t k = 0; k < adjacent.size(); ++k)
      for (std::size_t q : adjacent[k]) ++count(k, owner[q]);
  }
  std::size_t& count(std::size_t pose, int block) {
    for (auto& e : into_[pose])
      if (e.first == block) return e.second;
    into_[pose].emplace_back(block, 0);
    return into_[pose].back().second;
  }
  std::size_t links(std::size_t pose, int block) const {
    for (const auto& e : into_[pose])
      if (e.first == block) return e.second;
    return 0;
  }
  const std::vector<std::pair<int, std::size_t>>& of(std::size_t pose) const { return into_[pose]; }

 private:
  std::vector<std::vector<std::pair<int, std::size_t>>> into_;
};

std::vector<std::size_t> block_sizes(const std::vector<int>& owner, int num_blocks) {
  std::vector<std::size_t> size(static_cast<std::size_t>(num_blocks), 0);
  for (int b : owner) ++size[static_cast<std::size_t>(b)];
  return size;
}

// Poses whose block differs between `before` and `after` (a pose moved and moved back has not).
std::size_t poses_changed(const std::vector<int>& before, const std::vector<int>& after) {
  std::size_t changed = 0;
  for (std::size_t k = 0; k < after.size(); ++k) changed += after[k] != before[k] ? 1 : 0;
  return changed;
}

double balance_bound(std::size_t n, int num_blocks, const RebalanceOptions& options) {
  return (1.0 + options.slack) *
         std::ceil(static_cast<double>(n) / static_cast<double>(num_blocks));
}

// The balance moves (rebalance_blocks' first part). Returns the poses moved.
std::size_t balance_moves(const std::vector<std::vector<std::size_t>>& adjacent,
                          std::vector<int>& owner, std::vector<std::size_t>& size, int num_blocks,
                          double bound, const RebalanceOptions& options) {
  const std::size_t n = owner.size();
  const std::size_t blocks = static_cast<std::size_t>(num_blocks);
  auto over = [&](std::size_t s) {
    return static_cast<double>(s) > bound + static_cast<double>(options.min_excess);
  };
  // Per pair of blocks (b, c), the poses of b that may move and have a measurement into c, in
  // id order. Kept up to date move by move, so a move costs the moved pose's degree, not a
  // scan of the graph (which made a call that moves M poses O(M n)).
  BlockLinks into(adjacent, owner);
  std::vector<std::set<std::size_t>> border(blocks * blocks);
  std::vector<char> moved(n, 0);
  for (std::size_t k = 0; k < n; ++k)
    for (const auto& [c, links] : into.of(k))
      if (c != owner[k] && links > 0)
        border[static_cast<std::size_t>(owner[k]) * blocks + static_cast<std::size_t>(c)].insert(k);
  // Each pass moves one pose out of the largest over-full block that has a lighter neighbour
  // block: the lowest-id pose among those with a measurement into the lightest block at least
  // two poses lighter, to the first such block among its measurements. A pose moves at most
  // once per call, so the loop ends.
  std::size_t count = 0;
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
      for (const auto& [c, links] : into.of(best_pose))
        if (c != big && links > 0)
          border[bg * blocks + static_cast<std::size_t>(c)].erase(best_pose);
      owner[best_pose] = best_block;
      moved[best_pose] = 1;
      for (std::size_t q : adjacent[best_pose]) {
        const std::size_t b = static_cast<std::size_t>(owner[q]);
        if (--into.count(q, big) == 0 && b != bg) border[b * blocks + bg].erase(q);
        if (++into.count(q, best_block) == 1 && b != static_cast<std::size_t>(best_block) &&
            !moved[q])
          border[b * blocks + static_cast<std::size_t>(best_block)].insert(q);
      }
      --size[bg];
      ++size[static_cast<std::size_t>(best_block)];
      ++count;
      any = true;
      break;
    }
    if (!any) break;
  }
  return count;
}

// The bounds by chains of blocks (rebalance_blocks' second part, with the cut refinement on):
// every block above `upper` poses gives border poses away until it holds `upper`, and every
// block under `lower` takes border poses until it holds `lower`. A pose moves only to a block
// it has a measurement into; when the neighbouring block cannot take it (at `upper` itself) or
// cannot spare one (at `lower`), poses pass along the shortest chain of blocks to the nearest
// block below `upper` (above `lower`), one hop each, so only the two blocks at the ends of the
// chain change size. Per hop the pose moved is the border pose whose move cuts the fewest
// measurements (links into the receiving block minus links in its own; lowest id on ties). A
// block whose chains of measurements reach no such block stays out of the bound (a piece of
// the graph, e.g. a robot that has met no other, whose blocks are all at or past it). Each
// chain brings one block one pose closer to the bound and none further, so the loop ends.
// Returns the single-pose moves made.
std::size_t chain_moves(const std::vector<std::vector<std::size_t>>& adjacent,
                        std::vector<int>& owner, std::vector<std::size_t>& size, int num_blocks,
                        std::size_t lower, std::size_t upper) {
  const std::size_t n = owner.size();
  const std::size_t blocks = static_cast<std::size_t>(num_blocks);
  BlockLinks into(adjacent, owner);
  // (b, c): the poses of b with a measurement into c. Not empty exactly when (c, b) is not.
  std::vector<std::set<std::size_t>> border(blocks * blocks);
  for (std::size_t k = 0; k < n; ++k)
    for (const auto& [c, links] : into.of(k))
      if (c != owner[k] && links > 0)
        border[static_cast<std::size_t>(owner[k]) * blocks + static_cast<std::size_t>(c)].insert(k);
  auto move = [&](std::size_t v, std::size_t to) {
    const std::size_t from = static_cast<std::size_t>(owner[v]);
    for (const auto& [c, links] : into.of(v))
      if (static_cast<std::size_t>(c) != from && links > 0)
        border[from * blocks + static_cast<std::size_t>(c)].erase(v);
    owner[v] = static_cast<int>(to);
    for (const auto& [c, links] : into.of(v))
      if (static_cast<std::size_t>(c) != to && links > 0)
        border[to * blocks + static_cast<std::size_t>(c)].insert(v);
    for (std::size_t q : adjacent[v]) {
      const std::size_t b = static_cast<std::size_t>(owner[q]);
      if (--into.count(q, static_cast<int>(from)) == 0 && b != from)
        border[b * blocks + from].erase(q);
      if (++into.count(q, static_cast<int>(to)) == 1 && b != to) border[b * blocks + to].insert(q);
    }
    --size[from];
    ++size[to];
  };
  // One pose from block c to block `to` (c has a border pose into it).
  auto hop = [&](std::size_t c, std::size_t to) {
    std::size_t pose = n;
    long best = 0;
    for (std::size_t v : border[c * blocks + to]) {
      const long gain = static_cast<long>(into.links(v, static_cast<int>(to))) -
                        static_cast<long>(into.links(v, static_cast<int>(c)));
      if (pose == n || gain > best) {
        pose = v;
        best = gain;
      }
    }
    if (pose < n) move(pose, to);  // (a block on the chain keeps its border poses to the next)
  };
  // Breadth first from `from` over the blocks linked by border poses, in id order: the first
  // block for which `found` holds, or `blocks`; prev[] leads back to `from`.
  std::vector<std::size_t> prev(blocks), queue;
  std::vector<char> seen(blocks);
  auto nearest = [&](std::size_t from, auto found) {
    std::fill(seen.begin(), seen.end(), 0);
    seen[from] = 1;
    queue.assign(1, from);
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::size_t b = queue[head];
      for (std::size_t c = 0; c < blocks; ++c) {
        if (seen[c] || border[b * blocks + c].empty()) continue;
        seen[c] = 1;
        prev[c] = b;
        if (found(c)) return c;
        queue.push_back(c);
      }
    }
    return blocks;
  };
  std::size_t count = 0;
  // A block that no chain links to a block that can take (give) a pose: moves elsewhere never
  // change that (a block that could pass a pose towards it would have been found).
  std::vector<char> stuck_over(blocks, 0), stuck_under(blocks, 0);
  for (;;) {
    // The largest block above `upper`, else the smallest under `lower` (lowest id on ties).
    std::size_t heavy = blocks, light = blocks;
    for (std::size_t b = 0; b < blocks; ++b) {
      if (!stuck_over[b] && size[b] > upper && (heavy == blocks || size[b] > size[heavy]))
        heavy = b;
      if (!stuck_under[b] && size[b] < lower && (light == blocks || size[b] < size[light]))
        light = b;
    }
    if (heavy != blocks) {
      const std::size_t to = nearest(heavy, [&](std::size_t c) { return size[c] < upper; });
      if (to == blocks) {
        stuck_over[heavy] = 1;
        continue;
      }
      // The chain heavy -> ... -> to, moved from its far end so each hop's giver has a pose.
      for (std::size_t c = to; c != heavy; c = prev[c], ++count) hop(prev[c], c);
    } else if (light != blocks) {
      const std::size_t from = nearest(light, [&](std::size_t c) { return size[c] > lower; });
      if (from == blocks) {
        stuck_under[light] = 1;
        continue;
      }
      for (std::size_t c = from; c != light; c = prev[c], ++count) hop(c, prev[c]);
    } else {
      break;
    }
  }
  return count;
}

std::size_t refine_with(const std::vector<std::vector<std::size_t>>& adjacent,
                        std::vector<int>& owner, int num_blocks, std::size_t bound,
                        std::size_t lower, const RebalanceOptions& options) {
  lower = std::max<std::size_t>(lower, 1);
  const std::size_t n = owner.size();
  const std::vector<int> start = owner;
  std::vector<std::size_t> size = block_sizes(owner, num_blocks);
  BlockLinks into(adjacent, owner);
  // The best move of a pose: to a block it has a measurement into, below `bound`, from a
  // block above `lower`; the most cut measurements removed (links there minus links in
  // its own block), then the lighter block, then the lower one. {gain, block}; block -1: none.
  auto best_move = [&](std::size_t v) -> std::pair<long, int> {
    const int own = owner[v];
    if (size[static_cast<std::size_t>(own)] <= lower) return {0, -1};
    const long inside = static_cast<long>(into.links(v, own));
    long best_gain = 0;
    int best = -1;
    for (const auto& [c, links] : into.of(v)) {
      if (c == own || links == 0 || size[static_cast<std::size_t>(c)] >= bound) continue;
      const long gain = static_cast<long>(links) - inside;
      if (best < 0 || gain > best_gain ||
          (gain == best_gain && std::make_pair(size[static_cast<std::size_t>(c)], c) <
                                    std::make_pair(size[static_cast<std::size_t>(best)], best))) {
        best_gain = gain;
        best = c;
      }
    }
    return {best_gain, best};
  };
  auto apply = [&](std::size_t v, int to) {
    const int from = owner[v];
    for (std::size_t q : adjacent[v]) {
      --into.count(q, from);
      ++into.count(q, to);
    }
    owner[v] = to;
    --size[static_cast<std::size_t>(from)];
    ++size[static_cast<std::size_t>(to)];
  };
  // Heap entries (gain, -id, stamp): the highest gain first, then the lowest id. An entry is
  // current while its pose's stamp is unchanged (a neighbour's move changes it).
  using Entry = std::tuple<long, long, std::size_t>;
  std::vector<std::size_t> stamp(n, 0);
  for (int pass = 0; pass < options.max_passes; ++pass) {
    std::priority_queue<Entry> heap;
    std::vector<char> locked(n, 0);
    auto push = [&](std::size_t v) {
      const auto [gain, to] = best_move(v);
      if (to >= 0) heap.emplace(gain, -static_cast<long>(v), stamp[v]);
    };
    for (std::size_t v = 0; v < n; ++v) push(v);
    std::vector<std::pair<std::size_t, int>> moves;  // (pose, its block before the move)
    long total = 0, best_total = 0;
    std::size_t best_length = 0, since_best = 0;
    while (!heap.empty()) {
      const auto [gain, neg_id, entry_stamp] = heap.top();
      heap.pop();
      const std::size_t v = static_cast<std::size_t>(-neg_id);
      if (locked[v] || entry_stamp != stamp[v]) continue;
      const auto [now_gain, to] = best_move(v);
      if (to < 0) continue;
      if (now_gain != gain) {  // a block filled or emptied since the entry was made
        heap.emplace(now_gain, neg_id, stamp[v]);
        continue;
      }
      moves.emplace_back(v, owner[v]);
      apply(v, to);
      locked[v] = 1;
      total += now_gain;
      for (std::size_t q : adjacent[v]) {
        ++stamp[q];
        if (!locked[q]) push(q);
      }
      if (total > best_total) {
        best_total = total;
        best_length = moves.size();
        since_best = 0;
      } else if (++since_best >= options.pass_patience) {
        break;
      }
    }
    // Back to the best prefix (the shortest one reaching the best cut).
    while (moves.size() > best_length) {
      apply(moves.back().first, moves.back().second);
      for (std::size_t q : adjacent[moves.back().first]) ++stamp[q];
      moves.pop_back();
    }
    if (best_total <= 0) break;
  }
  return poses_changed(start, owner);
}

}  // namespace

std::size_t cut_measurements(const PoseGraph& graph, const std::vector<int>& owner) {
  std::size_t cut = 0;
  for (const Measurement& m : graph.measurements) cut += owner[m.i] != owner[m.j] ? 1 : 0;
  return cut;
}

std::size_t refine_cut(const PoseGraph& graph, std::vector<int>& owner, int num_blocks,
                       std::size_t bound, std::size_t lower, const RebalanceOptions& options) {
  options.validate();
  if (owner.size() != graph.num_poses || num_blocks <= 1) return 0;
  return refine_with(adjacency(graph), owner, num_blocks, bound, lower, options);
}

RebalanceResult rebalance_blocks(const PoseGraph& graph, std::vector<int>& owner, int num_blocks,
                                 const RebalanceOptions& options) {
  options.validate();
  RebalanceResult res;
  const std::size_t n = graph.num_poses;
  if (owner.size() != n || num_blocks <= 0) return res;
  std::vector<std::size_t> size = block_sizes(owner, num_blocks);
  res.largest_before = *std::max_element(size.begin(), size.end());
  res.largest_after = res.largest_before;
  res.smallest_after = *std::min_element(size.begin(), size.end());
  if (!options.enabled || num_blocks == 1) return res;
  const double bound = balance_bound(n, num_blocks, options);
  const double full = bound + static_cast<double>(options.min_excess);
  const bool refine = options.cut_fraction < 1.0;
  const bool over = std::any_of(size.begin(), size.end(),
                                [&](std::size_t s) { return static_cast<double>(s) > full; });
  // The floor, (1 - slack) floor(n / N) poses: with the cut refinement on, no block stays
  // under it (chain_moves), and the refinement takes none below it (a cut with no lower bound
  // is smallest with a block nearly empty, its agent idle: a robot that stopped publishing
  // lost all but 3 of its block's poses to the others).
  const double low_bound =
      (1.0 - options.slack) * std::floor(static_cast<double>(n) / static_cast<double>(num_blocks));
  const std::size_t lower = low_bound > 1.0 ? static_cast<std::size_t>(std::floor(low_bound)) : 1;
  const bool under =
      refine && std::any_of(size.begin(), size.end(), [&](std::size_t s) { return s < lower; });
  auto cut_high = [&](std::size_t cut) {
    return refine && static_cast<double>(cut) >
                         options.cut_fraction * static_cast<double>(graph.measurements.size());
  };
  std::size_t cut = 0;
  if (refine) {
    cut = cut_measurements(graph, owner);
    res.cut_before = res.cut_after = cut;
  }
  // Nothing over the bound, nothing under the floor and the cut low (most steps): done before
  // the graph's adjacency is built.
  if (!over && !under && !cut_high(cut)) return res;
  const std::vector<std::vector<std::size_t>> adjacent = adjacency(graph);
  const std::vector<int> start = refine ? owner : std::vector<int>{};
  if (over) res.moved = balance_moves(adjacent, owner, size, num_blocks, bound, options);
  if (refine) {
    // What the balance moves left over the bound (no lighter neighbour) or under the floor
    // goes by chains of blocks.
    const std::size_t upper = static_cast<std::size_t>(std::floor(full));
    if (std::any_of(size.begin(), size.end(),
                    [&](std::size_t s) { return s < lower || s > upper; }))
      res.chain_moves = chain_moves(adjacent, owner, size, num_blocks, lower, upper);
    if (res.moved > 0 || res.chain_moves > 0) cut = cut_measurements(graph, owner);
    if (cut_high(cut)) {
      res.refined = true;
      res.cut_moved = refine_with(adjacent, owner, num_blocks, upper, lower, options);
      if (res.cut_moved > 0) cut = cut_measurements(graph, owner);
    }
    // Poses that changed block in the call (a pose moved and moved back has not).
    res.moved = poses_changed(start, owner);
    res.cut_after = cut;
  }
  size = block_sizes(owner, num_blocks);
  res.largest_after = *std::max_element(size.begin(), size.end());
  res.smallest_after = *std::min_element(size.begin(), size.end());
  return res;
}

void assign_new_poses(const PoseGraph& graph, std::vector<int>& owner,
                      const std::vector<int>& robot_block, const RebalanceOptions& options) {
  const std::size_t first = owner.size();
  const bool by_links = options.enabled && options.place_by_links && options.cut_fraction < 1.0;
  if (!by_links) {
    for (std::size_t k = first; k < graph.num_poses; ++k) owner.push_back(robot_block[k - first]);
    return;
  }
  // The new poses' measurements to poses with a block, in id order of the new pose.
  std::vector<std::vector<std::size_t>> earlier(graph.num_poses - first);
  for (const Measurement& m : graph.measurements) {
    const std::size_t hi = std::max(m.i, m.j), lo = std::min(m.i, m.j);
    if (hi >= first) earlier[hi - first].push_back(lo);
  }
  // A block with no pose yet (a robot that just joined) takes its robot's first pose whatever
  // its links: otherwise a robot whose first pose links to another's (odometry across robots)
  // would leave its agent an empty block for good.
  std::vector<std::size_t> size;
  auto grow = [&](int b) {
    if (static_cast<std::size_t>(b) >= size.size()) size.resize(static_cast<std::size_t>(b) + 1, 0);
    ++size[static_cast<std::size_t>(b)];
  };
  for (int b : owner) grow(b);
  std::vector<std::pair<int, std::size_t>> count;
  for (std::size_t k = first; k < graph.num_poses; ++k) {
    const int own = robot_block[k - first];
    if (static_cast<std::size_t>(own) >= size.size() || size[static_cast<std::size_t>(own)] == 0) {
      owner.push_back(own);
      grow(own);
      continue;
    }
    count.clear();
    for (std::size_t q : earlier[k - first]) {
      const int c = owner[q];
      auto it =
          std::find_if(count.begin(), count.end(), [&](const auto& e) { return e.first == c; });
      if (it == count.end())
        count.emplace_back(c, 1);
      else
        ++it->second;
    }
    // Most links; on a tie the robot's block if it is among them, else the lowest block.
    int block = own;
    std::size_t most = 0;
    for (const auto& [c, links] : count)
      if (links > most || (links == most && block != own && (c == own || c < block))) {
        most = links;
        block = c;
      }
    owner.push_back(block);
    grow(block);
  }
}

}  // namespace tessera
