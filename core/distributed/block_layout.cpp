#include <algorithm>
#include <set>
#include <string>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

int BlockLayout::adjacency_index(int b, int a) const {
  const auto& adj = adjacent[static_cast<std::size_t>(b)];
  auto it = std::lower_bound(adj.begin(), adj.end(), a);
  return (it != adj.end() && *it == a) ? static_cast<int>(it - adj.begin()) : -1;
}

namespace {

std::size_t first_of(const Measurement& m) {
  return m.i;
}
std::size_t second_of(const Measurement& m) {
  return m.j;
}
std::size_t first_of(const std::pair<std::uint32_t, std::uint32_t>& e) {
  return e.first;
}
std::size_t second_of(const std::pair<std::uint32_t, std::uint32_t>& e) {
  return e.second;
}

template <class Edge>
BlockLayout layout_of(std::size_t num_poses, const std::vector<Edge>& measurements,
                      const std::vector<int>& assignment) {
  if (assignment.size() != num_poses)
    throw InputError("partition: assignment has " + std::to_string(assignment.size()) +
                     " entries for " + std::to_string(num_poses) + " poses");
  BlockLayout L;
  int N = 0;
  for (int b : assignment) {
    if (b < 0) throw InputError("partition: negative block id " + std::to_string(b));
    N = std::max(N, b + 1);
  }
  L.num_blocks = N;
  L.owner = assignment;
  L.poses.assign(static_cast<std::size_t>(N), {});
  for (std::size_t i = 0; i < num_poses; ++i)
    L.poses[static_cast<std::size_t>(assignment[i])].push_back(i);
  for (int b = 0; b < N; ++b)
    if (L.poses[static_cast<std::size_t>(b)].empty())
      throw InputError("partition: block " + std::to_string(b) + " is empty");
  // publish[b][a] = poses of b that a needs.
  std::vector<std::vector<std::set<std::size_t>>> publish(
      static_cast<std::size_t>(N), std::vector<std::set<std::size_t>>(static_cast<std::size_t>(N)));
  for (const auto& m : measurements) {
    const std::size_t i = first_of(m), j = second_of(m);
    if (i >= num_poses || j >= num_poses)
      throw InputError("partition: measurement id out of range");
    const int bi = assignment[i], bj = assignment[j];
    if (bi == bj) continue;
    publish[static_cast<std::size_t>(bi)][static_cast<std::size_t>(bj)].insert(i);
    publish[static_cast<std::size_t>(bj)][static_cast<std::size_t>(bi)].insert(j);
  }
  L.adjacent.assign(static_cast<std::size_t>(N), {});
  L.public_to.assign(static_cast<std::size_t>(N), {});
  for (int b = 0; b < N; ++b)
    for (int a = 0; a < N; ++a) {
      const auto& s = publish[static_cast<std::size_t>(b)][static_cast<std::size_t>(a)];
      if (s.empty()) continue;
      L.adjacent[static_cast<std::size_t>(b)].push_back(a);
      L.public_to[static_cast<std::size_t>(b)].emplace_back(s.begin(), s.end());
    }
  L.colour.assign(static_cast<std::size_t>(N), -1);
  for (int b = 0; b < N; ++b) {
    std::vector<bool> used(static_cast<std::size_t>(N) + 1, false);
    for (int a : L.adjacent[static_cast<std::size_t>(b)])
      if (L.colour[static_cast<std::size_t>(a)] >= 0)
        used[static_cast<std::size_t>(L.colour[static_cast<std::size_t>(a)])] = true;
    int c = 0;
    while (used[static_cast<std::size_t>(c)]) ++c;
    L.colour[static_cast<std::size_t>(b)] = c;
    if (static_cast<int>(L.colour_classes.size()) <= c)
      L.colour_classes.resize(static_cast<std::size_t>(c) + 1);
    L.colour_classes[static_cast<std::size_t>(c)].push_back(b);
  }
  return L;
}

}  // namespace

BlockLayout make_block_layout(std::size_t num_poses, const std::vector<Measurement>& measurements,
                              const std::vector<int>& assignment) {
  return layout_of(num_poses, measurements, assignment);
}

BlockLayout make_block_layout(std::size_t num_poses,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& endpoints,
                              const std::vector<int>& assignment) {
  return layout_of(num_poses, endpoints, assignment);
}

}  // namespace tessera
