#include "runtime/local_share.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tessera/util/input_error.hpp>

#include "generate/robot_ranges.hpp"

namespace tessera::agent {

RobotShare robot_share(const PoseGraph& graph, std::uint32_t robot, std::uint32_t num_robots) {
  if (num_robots < 1 || num_robots > graph.num_poses)
    throw InputError(graph.source, 0,
                     "cannot split " + std::to_string(graph.num_poses) + " poses among " +
                         std::to_string(num_robots) + " robots");
  RobotShare s;
  s.d = graph.d;
  s.num_poses = graph.num_poses;
  s.begin = static_cast<std::uint32_t>(robot_begin(robot, graph.num_poses, num_robots));
  s.end = static_cast<std::uint32_t>(robot_begin(robot + 1, graph.num_poses, num_robots));
  for (std::size_t k = 0; k < graph.measurements.size(); ++k) {
    const Measurement& m = graph.measurements[k];
    if (m.i >= s.begin && m.i < s.end) {
      s.measurements.push_back(m);
      s.measurement_index.push_back(k);
    }
  }
  if (graph.has_initial())
    s.initial.assign(graph.initial.begin() + s.begin, graph.initial.begin() + s.end);
  return s;
}

HandoffPlan plan_handoff(const RobotShare& share, const std::vector<std::uint32_t>& owner,
                         std::uint32_t recipient) {
  HandoffPlan plan;
  for (std::size_t k = 0; k < share.measurements.size(); ++k) {
    const Measurement& m = share.measurements[k];
    if (owner[m.i] == recipient || owner[m.j] == recipient) {
      plan.measurements.push_back(&m);
      plan.measurement_index.push_back(share.measurement_index[k]);
    }
  }
  if (!share.initial.empty())
    for (std::uint32_t id = share.begin; id < share.end; ++id)
      if (owner[id] == recipient) plan.poses.emplace_back(id, &share.initial[id - share.begin]);
  if (!share.known_initial.empty())
    for (std::uint32_t id = share.begin; id < share.end; ++id)
      if (owner[id] == recipient)
        plan.known_poses.emplace_back(id, &share.known_initial[id - share.begin]);
  return plan;
}

namespace {

// The poses of `own_range` (share's [begin, end), or empty: none) and those `field` of the
// hand-offs carries, in the order of `owned`.
std::vector<Pose> owned_poses(const std::vector<Pose>& own_range, const RobotShare& share,
                              const std::vector<std::uint32_t>& owner, std::uint32_t self,
                              const std::vector<ReceivedHandoff>& received,
                              const std::vector<std::uint32_t>& owned,
                              std::vector<std::pair<std::uint32_t, Pose>> ReceivedHandoff::*field,
                              const std::string& what) {
  std::vector<Pose> out;
  if (own_range.empty()) return out;
  std::vector<const Pose*> slot(owner.size(), nullptr);
  for (std::uint32_t id = share.begin; id < share.end; ++id)
    if (owner[id] == self) slot[id] = &own_range[id - share.begin];
  for (const ReceivedHandoff& h : received)
    for (const auto& [id, pose] : h.*field) {
      if (id >= owner.size() || owner[id] != self)
        throw std::runtime_error("agent " + std::to_string(h.sender) + " handed over " + what +
                                 " " + std::to_string(id) + " which agent " + std::to_string(self) +
                                 " does not own");
      if (slot[id])
        throw std::runtime_error(what + " " + std::to_string(id) + " was handed over twice");
      slot[id] = &pose;
    }
  out.reserve(owned.size());
  for (std::uint32_t id : owned) {
    if (!slot[id])
      throw std::runtime_error(what + " " + std::to_string(id) +
                               " was never handed over to agent " + std::to_string(self));
    out.push_back(*slot[id]);
  }
  return out;
}

}  // namespace

AgentLocalData assemble_local(const RobotShare& share, const std::vector<std::uint32_t>& owner,
                              std::uint32_t self, std::uint32_t num_agents,
                              std::vector<ReceivedHandoff> received, const RunOptions& options) {
  AgentLocalData local;
  local.agent_id = self;
  local.num_agents = num_agents;
  local.d = share.d;
  local.num_poses = share.num_poses;
  local.owner = owner;
  local.options = options;
  for (std::uint32_t id = 0; id < owner.size(); ++id)
    if (owner[id] == self) local.owned.push_back(id);

  // (file position, measurement) from our own share and from every sender.
  std::vector<std::pair<std::uint64_t, const Measurement*>> all;
  HandoffPlan mine = plan_handoff(share, owner, self);
  for (std::size_t k = 0; k < mine.measurements.size(); ++k)
    all.emplace_back(mine.measurement_index[k], mine.measurements[k]);
  for (const ReceivedHandoff& h : received) {
    for (std::size_t k = 0; k < h.measurements.size(); ++k) {
      const Measurement& m = h.measurements[k];
      if (m.i >= owner.size() || m.j >= owner.size() || (owner[m.i] != self && owner[m.j] != self))
        throw std::runtime_error("agent " + std::to_string(h.sender) + " handed over measurement " +
                                 std::to_string(m.i) + "-" + std::to_string(m.j) +
                                 " which touches no pose of agent " + std::to_string(self));
      all.emplace_back(h.measurement_index[k], &m);
    }
  }
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (k > 0 && all[k].first == all[k - 1].first)
      throw std::runtime_error("measurement #" + std::to_string(all[k].first) +
                               " was received twice");
    local.measurements.push_back(*all[k].second);
    local.measurement_index.push_back(all[k].first);
  }

  // Initial poses: from our own range, or handed over by the robot that had them.
  local.initial = owned_poses(share.initial, share, owner, self, received, local.owned,
                              &ReceivedHandoff::poses, "initial pose");
  local.known_initial = owned_poses(share.known_initial, share, owner, self, received, local.owned,
                                    &ReceivedHandoff::known_poses, "known inliers' start pose");
  return local;
}

}  // namespace tessera::agent
