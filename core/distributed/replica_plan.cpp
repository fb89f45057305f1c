#include <algorithm>
#include <string>
#include <tessera/distributed/replica_plan.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

std::vector<std::vector<std::uint32_t>> replica_holders(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint32_t>& owner, std::uint32_t num_agents, std::uint32_t replicas) {
  const std::size_t N = num_agents;
  for (std::size_t v = 0; v < owner.size(); ++v)
    if (owner[v] >= num_agents)
      throw InputError("replica plan: pose " + std::to_string(v) + " has owner " +
                       std::to_string(owner[v]) + ", not an agent id");
  // cut[a][b]: measurements joining a's and b's poses.
  std::vector<std::vector<std::size_t>> cut(N, std::vector<std::size_t>(N, 0));
  for (const auto& [i, j] : structure) {
    if (i >= owner.size() || j >= owner.size())
      throw InputError("replica plan: measurement " + std::to_string(i) + "-" + std::to_string(j) +
                       " names a pose out of range");
    const std::uint32_t a = owner[i], b = owner[j];
    if (a == b) continue;
    ++cut[a][b];
    ++cut[b][a];
  }
  const std::size_t want = std::min<std::size_t>(replicas, N > 0 ? N - 1 : 0);
  std::vector<std::vector<std::uint32_t>> holders(N);
  for (std::uint32_t a = 0; a < N; ++a) {
    std::vector<std::uint32_t> order;
    for (std::uint32_t b = 0; b < N; ++b)
      if (b != a && cut[a][b] > 0) order.push_back(b);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t x, std::uint32_t y) { return cut[a][x] > cut[a][y]; });
    if (order.size() > want) order.resize(want);
    for (std::uint32_t k = 1; order.size() < want && k < N; ++k) {
      const std::uint32_t b = static_cast<std::uint32_t>((a + k) % N);
      if (std::find(order.begin(), order.end(), b) == order.end()) order.push_back(b);
    }
    holders[a] = std::move(order);
  }
  return holders;
}

std::vector<std::uint32_t> replicas_kept_by(const std::vector<std::vector<std::uint32_t>>& holders,
                                            std::uint32_t holder) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t a = 0; a < holders.size(); ++a)
    if (std::find(holders[a].begin(), holders[a].end(), holder) != holders[a].end())
      out.push_back(a);
  return out;
}

}  // namespace tessera
