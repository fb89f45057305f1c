#include "runtime/survivor_step.hpp"

#include <algorithm>
#include <tessera/partition/survivor_repartition.hpp>

namespace tessera::coordinator {

SurvivorAssignment reassign_for_survivors(const GraphStructure& graph,
                                          const std::vector<std::uint32_t>& owner,
                                          std::uint32_t num_agents,
                                          const std::vector<std::uint32_t>& lost,
                                          std::uint32_t epoch) {
  const std::vector<int> old(owner.begin(), owner.end());
  std::vector<int> gone(lost.begin(), lost.end());
  std::sort(gone.begin(), gone.end());
  gone.erase(std::unique(gone.begin(), gone.end()), gone.end());
  const SurvivorRepartitionResult r =
      repartition_for_survivors(graph, old, static_cast<int>(num_agents), gone);
  SurvivorAssignment out;
  out.epoch = epoch;
  out.owner.assign(r.owner.begin(), r.owner.end());
  out.survivors.assign(r.survivors.begin(), r.survivors.end());
  out.lost.assign(gone.begin(), gone.end());
  out.moved_poses = r.moved_poses;
  out.cut_edges = r.metrics.cut_edges;
  out.ms = r.time_ms;
  return out;
}

}  // namespace tessera::coordinator
