#include "agent/round_loop.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <variant>

namespace tessera::agent {

namespace {

// For each neighbouring agent, the ids of our owned poses it needs (endpoints of shared
// measurements), ascending.
std::map<std::uint32_t, std::vector<std::uint32_t>> boundary_by_neighbour(
    const AgentLocalData& local) {
  std::map<std::uint32_t, std::set<std::uint32_t>> sets;
  for (const Measurement& m : local.measurements) {
    const auto i = static_cast<std::uint32_t>(m.i), j = static_cast<std::uint32_t>(m.j);
    const std::uint32_t oi = local.owner[i], oj = local.owner[j];
    if (oi == local.agent_id && oj != local.agent_id) sets[oj].insert(i);
    if (oj == local.agent_id && oi != local.agent_id) sets[oi].insert(j);
  }
  std::map<std::uint32_t, std::vector<std::uint32_t>> out;
  for (auto& [b, s] : sets) out[b] = std::vector<std::uint32_t>(s.begin(), s.end());
  return out;
}

// The poses of a neighbour's block we should receive: its owned endpoints of our measurements.
std::map<std::uint32_t, std::vector<std::uint32_t>> expected_from_neighbours(
    const AgentLocalData& local) {
  std::map<std::uint32_t, std::set<std::uint32_t>> sets;
  for (const Measurement& m : local.measurements) {
    const auto i = static_cast<std::uint32_t>(m.i), j = static_cast<std::uint32_t>(m.j);
    const std::uint32_t oi = local.owner[i], oj = local.owner[j];
    if (oi == local.agent_id && oj != local.agent_id) sets[oj].insert(j);
    if (oj == local.agent_id && oi != local.agent_id) sets[oi].insert(i);
  }
  std::map<std::uint32_t, std::vector<std::uint32_t>> out;
  for (auto& [b, s] : sets) out[b] = std::vector<std::uint32_t>(s.begin(), s.end());
  return out;
}

}  // namespace

// PLACEHOLDER until core's agent state machine is plugged in: one round in which every
// agent sends its boundary poses (rank r = d, i.e. the poses themselves) to each
// neighbour and a status to everyone, and checks it received exactly what it expected.
RoundLoopResult run_round_loop(const AgentLocalData& local, ProtocolChannel& channel,
                               double receive_timeout_s) {
  const int d = local.d;
  std::map<std::uint32_t, std::size_t> slot;  // owned pose id -> index in local.owned
  for (std::size_t k = 0; k < local.owned.size(); ++k) slot[local.owned[k]] = k;
  auto pose_of = [&](std::uint32_t id) {
    return local.initial.empty() ? Pose::identity(d) : local.initial[slot.at(id)];
  };

  for (const auto& [neighbour, ids] : boundary_by_neighbour(local)) {
    PoseBlockMessage block;
    block.round = 0;
    block.sender = local.agent_id;
    block.kind = BlockKind::kY;
    block.rank = static_cast<std::uint32_t>(d);
    block.dim = static_cast<std::uint32_t>(d);
    block.pose_ids = ids;
    for (std::uint32_t id : ids) {
      Pose p = pose_of(id);
      for (int c = 0; c < d; ++c)
        for (int r = 0; r < d; ++r) block.data.push_back(p.R(r, c));
      for (int r = 0; r < d; ++r) block.data.push_back(p.t(r));
    }
    channel.send(OutgoingMessage{block, false, {neighbour}});
  }
  RoundStatusMessage status;
  status.round = 0;
  status.sender = local.agent_id;
  status.done_vote = true;
  channel.send(OutgoingMessage{status, true, {}});

  auto expected = expected_from_neighbours(local);
  std::set<std::uint32_t> statuses_missing;
  for (std::uint32_t a = 0; a < local.num_agents; ++a)
    if (a != local.agent_id) statuses_missing.insert(a);
  while (!expected.empty() || !statuses_missing.empty()) {
    auto msg = channel.receive(receive_timeout_s);
    if (!msg) {
      std::string who;
      for (auto& [b, ids] : expected) who += " block from agent " + std::to_string(b) + ";";
      for (auto a : statuses_missing) who += " status from agent " + std::to_string(a) + ";";
      throw std::runtime_error("round 0: nothing received for " +
                               std::to_string(receive_timeout_s) + " s; still waiting for:" + who);
    }
    if (auto* block = std::get_if<PoseBlockMessage>(&*msg)) {
      auto it = expected.find(block->sender);
      if (it == expected.end())
        throw std::runtime_error("round 0: unexpected pose block from agent " +
                                 std::to_string(block->sender));
      if (block->pose_ids != it->second || block->rank != static_cast<std::uint32_t>(d))
        throw std::runtime_error("round 0: pose block from agent " + std::to_string(block->sender) +
                                 " does not hold the expected boundary poses");
      expected.erase(it);
    } else {
      statuses_missing.erase(std::get<RoundStatusMessage>(*msg).sender);
    }
  }

  RoundLoopResult result;
  result.rounds = 1;
  for (std::uint32_t id : local.owned) result.poses.push_back(pose_of(id));
  return result;
}

}  // namespace tessera::agent
