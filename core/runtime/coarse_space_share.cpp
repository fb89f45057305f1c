#include "runtime/coarse_space_share.hpp"

#include <cstddef>

namespace tessera::agent {

void keep_agent_share(CoarseSpace& space, const BlockLayout& layout, int agent,
                      const std::vector<Measurement>& measurements) {
  const std::size_t n = space.owner.size();
  const auto a = static_cast<std::size_t>(agent);
  std::vector<char> own(n, 0), keep(n, 0);
  for (std::size_t i : layout.poses[a]) own[i] = keep[i] = 1;
  for (int b : layout.adjacent[a]) {
    const int k = layout.adjacency_index(b, agent);
    for (std::size_t i : layout.public_to[static_cast<std::size_t>(b)][static_cast<std::size_t>(k)])
      keep[i] = 1;
  }
  for (const Measurement& m : measurements)
    if (m.i < n && m.j < n && (own[m.i] || own[m.j])) keep[m.i] = keep[m.j] = 1;

  std::vector<std::size_t> start(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i)
    start[i + 1] =
        start[i] + (keep[i] ? space.weight_start[i + 1] - space.weight_start[i] : std::size_t{0});
  std::vector<int> pieces;
  std::vector<double> weights;
  pieces.reserve(start[n]);
  weights.reserve(start[n]);
  for (std::size_t i = 0; i < n; ++i)
    if (keep[i])
      for (std::size_t e = space.weight_start[i]; e < space.weight_start[i + 1]; ++e) {
        pieces.push_back(space.weight_aggregate[e]);
        weights.push_back(space.weight[e]);
      }
  space.weight_start.swap(start);
  space.weight_aggregate.swap(pieces);
  space.weight.swap(weights);
  space.aggregate.clear();
  space.aggregate.shrink_to_fit();
}

}  // namespace tessera::agent
