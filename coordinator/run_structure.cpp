#include "coordinator/run_structure.hpp"

#include <algorithm>
#include <tessera/util/input_error.hpp>

namespace tessera::coordinator {

RunStructure merge_announcements(const std::vector<wire::AgentAnnouncement>& announcements,
                                 std::uint32_t num_agents, const std::string& run_id) {
  std::vector<const wire::AgentAnnouncement*> by_id(num_agents, nullptr);
  for (const auto& a : announcements) {
    const std::string who = "agent " + std::to_string(a.agent_id()) + " (pid " +
                            std::to_string(a.pid()) + " on " + a.host() + ")";
    if (a.num_agents() != num_agents)
      throw InputError(who + " was started for " + std::to_string(a.num_agents()) +
                       " robots, the coordinator expects " + std::to_string(num_agents) +
                       " agents");
    if (a.agent_id() >= num_agents)
      throw InputError(who + ": id is not below " + std::to_string(num_agents));
    if (by_id[a.agent_id()])
      throw InputError("two agents announced themselves as agent " + std::to_string(a.agent_id()) +
                       " (hosts " + by_id[a.agent_id()]->host() + " and " + a.host() + ")");
    by_id[a.agent_id()] = &a;
  }
  RunStructure rs;
  struct Edge {
    std::uint64_t index;
    std::uint32_t agent, i, j;
    bool known;
  };
  std::vector<Edge> edges;
  for (std::uint32_t k = 0; k < num_agents; ++k)
    if (!by_id[k]) throw InputError("no announcement from agent " + std::to_string(k));
  // n: an agent reading the whole file announces it; one reading only its robot's own file
  // announces 0 (it cannot know n), and n is then the end of the last agent's range.
  for (std::uint32_t k = 0; k < num_agents && rs.num_poses == 0; ++k)
    rs.num_poses = by_id[k]->num_poses();
  if (rs.num_poses == 0) rs.num_poses = by_id[num_agents - 1]->pose_end();
  for (std::uint32_t k = 0; k < num_agents; ++k) {
    const auto& a = *by_id[k];
    const std::string who = "agent " + std::to_string(k) + " (on " + a.host() + ")";
    if (k == 0) {
      rs.d = static_cast<int>(a.dim());
      if (rs.d != 2 && rs.d != 3)
        throw InputError(who + ": dimension " + std::to_string(a.dim()) + " is not 2 or 3");
    }
    if (static_cast<int>(a.dim()) != rs.d ||
        (a.num_poses() != 0 && a.num_poses() != rs.num_poses)) {
      throw InputError(who + " has a " + std::to_string(a.dim()) + "D graph of " +
                       std::to_string(a.num_poses()) + " poses, the run a " + std::to_string(rs.d) +
                       "D graph of " + std::to_string(rs.num_poses) +
                       " poses: were they given the same file?");
    }
    const std::size_t expected_begin = k == 0 ? 0 : by_id[k - 1]->pose_end();
    if (a.pose_begin() != expected_begin || a.pose_end() < a.pose_begin() ||
        (k + 1 == num_agents && a.pose_end() != rs.num_poses))
      throw InputError(who + " holds poses [" + std::to_string(a.pose_begin()) + ", " +
                       std::to_string(a.pose_end()) +
                       "), which does not continue the previous agents' ranges");
    if (a.edge_i().size() != a.edge_j().size() || a.edge_index().size() != a.edge_i().size())
      throw InputError(who + ": edge endpoint and index arrays differ in length");
    std::vector<std::uint64_t> known(a.known_inlier_index().begin(), a.known_inlier_index().end());
    std::sort(known.begin(), known.end());
    std::size_t flagged = 0;
    for (std::size_t e = 0; e < a.edge_i().size(); ++e) {
      if (a.edge_i()[e] >= rs.num_poses || a.edge_j()[e] >= rs.num_poses)
        throw InputError(who + ": edge endpoint out of range");
      const bool k_in = std::binary_search(known.begin(), known.end(), a.edge_index()[e]);
      flagged += k_in ? 1 : 0;
      edges.push_back({a.edge_index()[e], k, a.edge_i()[e], a.edge_j()[e], k_in});
    }
    if (flagged != known.size())
      throw InputError(who + ": a known-inlier flag names a measurement it does not hold");
    rs.hosts.push_back(a.host());
  }
  // Canonical order: the measurements' positions in the input, whatever the agents' order,
  // so the coordinator partitions (and every agent lays out) the graph as `tessera solve` does.
  std::stable_sort(edges.begin(), edges.end(),
                   [](const Edge& x, const Edge& y) { return x.index < y.index; });
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  pairs.reserve(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (e > 0 && edges[e].index == edges[e - 1].index)
      throw InputError("agents " + std::to_string(edges[e - 1].agent) + " and " +
                       std::to_string(edges[e].agent) + " both announced measurement #" +
                       std::to_string(edges[e].index) + ": were they given overlapping files?");
    pairs.emplace_back(edges[e].i, edges[e].j);
    if (edges[e].known) rs.known_inlier.push_back(static_cast<std::uint32_t>(e));
    rs.edge_i.push_back(edges[e].i);
    rs.edge_j.push_back(edges[e].j);
  }
  rs.num_measurements = pairs.size();
  rs.graph = make_graph_structure(rs.num_poses, pairs, "run '" + run_id + "'");
  return rs;
}

}  // namespace tessera::coordinator
