#pragma once
// What the coordinator learns from the agents' announcements: the whole graph's
// structure (edge endpoints only, never measurement values), checked for consistency.

#include <cstdint>
#include <string>
#include <tessera/partition/graph_structure.hpp>
#include <vector>

#include "tessera.h"

namespace tessera::coordinator {

struct RunStructure {
  int d = 0;
  std::size_t num_poses = 0;
  std::size_t num_measurements = 0;
  GraphStructure graph;
  std::vector<std::uint32_t> edge_i, edge_j;  ///< Every measurement's endpoints (input order).
  /// Positions (in edge_i order) of the measurements an agent flagged as known inliers.
  std::vector<std::uint32_t> known_inlier;
  std::vector<std::string> hosts;  ///< Per agent.
};

/// Checks the N announcements (one per agent id 0..N-1, any order) against each other:
/// same N, dimension and number of poses, pose ranges that tile 0..n-1 in agent order,
/// endpoints in range, no measurement index announced twice. The structure comes out in the
/// measurements' input order (edge_index), independent of the announcements' order; a known-
/// inlier flag must name one of its agent's measurements. Throws
/// InputError naming the offending agent.
RunStructure merge_announcements(const std::vector<wire::AgentAnnouncement>& announcements,
                                 std::uint32_t num_agents, const std::string& run_id);

}  // namespace tessera::coordinator
