#include "runtime/online_takeover.hpp"

#include <algorithm>
#include <stdexcept>
#include <tessera/partition/graph_structure.hpp>

namespace tessera::runtime {

OnlineTakeoverPlan plan_online_takeover(const PoseGraph& graph, const std::vector<int>& owner,
                                        const std::vector<std::uint32_t>& robots,
                                        const std::set<std::uint32_t>& lost,
                                        const SurvivorRepartitionOptions& options) {
  OnlineTakeoverPlan plan;
  plan.owner = owner;
  for (std::uint32_t r : lost) plan.adopter[r] = -1;
  const int num_blocks = static_cast<int>(robots.size());
  std::vector<int> lost_blocks;
  std::vector<char> is_lost(static_cast<std::size_t>(num_blocks), 0);
  for (int b = 0; b < num_blocks; ++b)
    if (lost.count(robots[static_cast<std::size_t>(b)]) > 0) {
      lost_blocks.push_back(b);
      is_lost[static_cast<std::size_t>(b)] = 1;
    }
  const bool any_live = lost_blocks.size() < static_cast<std::size_t>(num_blocks);
  const bool lost_poses = std::any_of(owner.begin(), owner.end(), [&](int b) {
    return b >= 0 && b < num_blocks && is_lost[static_cast<std::size_t>(b)];
  });
  if (!lost_poses) return plan;
  if (!any_live)
    throw std::runtime_error(
        "the lost agents' poses have no survivor block to go to (no "
        "survivor's robot has entered the graph yet)");
  const SurvivorRepartitionResult r = repartition_for_survivors(
      graph_structure_from_pose_graph(graph), owner, num_blocks, lost_blocks, options);
  plan.owner = r.owner;
  plan.moved = r.moved_poses;
  plan.cut_after = r.metrics.cut_edges;
  // The adopter of a lost robot: the block that took most of its poses (lowest on ties).
  for (int l : lost_blocks) {
    std::vector<std::size_t> took(static_cast<std::size_t>(num_blocks), 0);
    for (std::size_t k = 0; k < owner.size(); ++k)
      if (owner[k] == l) ++took[static_cast<std::size_t>(plan.owner[k])];
    int best = -1;
    for (int b = 0; b < num_blocks; ++b)
      if (took[static_cast<std::size_t>(b)] > 0 &&
          (best < 0 || took[static_cast<std::size_t>(b)] > took[static_cast<std::size_t>(best)]))
        best = b;
    plan.adopter[robots[static_cast<std::size_t>(l)]] = best;
  }
  return plan;
}

}  // namespace tessera::runtime
