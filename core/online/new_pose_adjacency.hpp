#pragma once
// Which new measurements touch each new pose: the graph walk both the composition of new poses
// (estimate_extension) and their least-squares placement (new_pose_placement) start from.

#include <algorithm>
#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// Entry k - first_new_pose lists, in file order, the measurements from index
/// first_new_measurement on that have new pose k (id >= first_new_pose) as an endpoint.
/// Measurements among old poses cannot place a new one, so earlier ones are not looked at.
inline std::vector<std::vector<std::size_t>> new_pose_adjacency(const PoseGraph& graph,
                                                                std::size_t first_new_pose,
                                                                std::size_t first_new_measurement) {
  const std::size_t m = first_new_pose;
  std::vector<std::vector<std::size_t>> touching(graph.num_poses - m);
  const std::size_t first = std::min(first_new_measurement, graph.measurements.size());
  for (std::size_t e = first; e < graph.measurements.size(); ++e) {
    const Measurement& me = graph.measurements[e];
    if (me.i >= m) touching[me.i - m].push_back(e);
    if (me.j >= m) touching[me.j - m].push_back(e);
  }
  return touching;
}

}  // namespace tessera
