#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/graph/connectivity.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

Measurement weighted_measurement(Measurement m, double weight) {
  const double w = std::max(weight, kMinInnerWeight);
  m.kappa *= w;
  m.tau *= w;
  return m;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> inlier_structure(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint64_t>& rejected) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> kept;
  kept.reserve(structure.size() - std::min(structure.size(), rejected.size()));
  auto r = rejected.begin();
  for (std::size_t e = 0; e < structure.size(); ++e) {
    while (r != rejected.end() && *r < e) ++r;
    if (r != rejected.end() && *r == e) continue;
    kept.push_back(structure[e]);
  }
  return kept;
}

PoseGraph weighted_graph(const PoseGraph& graph, const std::vector<double>& weights,
                         const std::vector<Pose>& initial) {
  if (weights.size() != graph.num_measurements())
    throw std::invalid_argument("weighted_graph: one weight per measurement expected");
  PoseGraph out;
  out.d = graph.d;
  out.num_poses = graph.num_poses;
  out.source = graph.source;
  out.initial = initial;
  out.measurements.reserve(weights.size());
  for (std::size_t e = 0; e < weights.size(); ++e)
    out.measurements.push_back(weighted_measurement(graph.measurements[e], weights[e]));
  return out;
}

PoseGraph known_subgraph(const PoseGraph& graph, const std::vector<bool>& keep) {
  PoseGraph out;
  out.d = graph.d;
  out.num_poses = graph.num_poses;
  out.source = graph.source;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e)
    if (keep[e]) out.measurements.push_back(graph.measurements[e]);
  return out;
}

PoseGraph inlier_graph(const PoseGraph& graph, const std::vector<std::size_t>& rejected,
                       const std::vector<Pose>& initial) {
  PoseGraph out;
  out.d = graph.d;
  out.num_poses = graph.num_poses;
  out.source = graph.source;
  out.initial = initial;
  out.measurements.reserve(graph.num_measurements() - rejected.size());
  std::size_t next = 0;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    if (next < rejected.size() && rejected[next] == e) {
      ++next;
      continue;
    }
    out.measurements.push_back(graph.measurements[e]);
  }
  return out;
}

void require_connected_inliers(const PoseGraph& graph, const PoseGraph& inliers,
                               std::size_t rejected) {
  const std::size_t parts = count_components(inliers);
  if (parts <= 1) return;
  throw InputError(graph.source, 0,
                   "robust solve: " + std::to_string(rejected) + " of " +
                       std::to_string(graph.num_measurements()) +
                       " measurements look like outliers, and the kept ones split the poses "
                       "into " +
                       std::to_string(parts) +
                       " unconnected parts, so no estimate is defined (too few consistent "
                       "measurements; try --known-inliers odometry or a larger "
                       "--inlier-threshold)");
}

}  // namespace tessera
