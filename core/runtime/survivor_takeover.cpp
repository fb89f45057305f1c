#include "runtime/survivor_takeover.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace tessera::agent {

void ReplicaStore::absorb_problem(std::uint32_t a, std::vector<Measurement> measurements,
                                  std::vector<std::uint64_t> measurement_index,
                                  const std::vector<std::uint32_t>& ids,
                                  const std::vector<double>& lifted, std::size_t width,
                                  std::uint32_t round) {
  if (measurements.size() != measurement_index.size() || lifted.size() != ids.size() * width)
    throw std::runtime_error("replica of agent " + std::to_string(a) + ": inconsistent sizes");
  Replica& r = by_agent_[a];
  r.measurements = std::move(measurements);
  r.measurement_index = std::move(measurement_index);
  r.has_problem = true;
  if (r.lifted.empty() || round >= r.round) {  // a newer pose replica may have come first
    r.round = round;
    for (std::size_t k = 0; k < ids.size(); ++k)
      r.lifted[ids[k]] = std::vector<double>(lifted.begin() + static_cast<long>(k * width),
                                             lifted.begin() + static_cast<long>((k + 1) * width));
  }
}

void ReplicaStore::absorb_poses(const PoseBlockMessage& m) {
  const std::size_t width = static_cast<std::size_t>(m.rank) * (m.dim + 1);
  if (m.data.size() != m.pose_ids.size() * width)
    throw std::runtime_error("pose replica of agent " + std::to_string(m.sender) +
                             " has the wrong size");
  Replica& r = by_agent_[m.sender];
  if (!r.lifted.empty() && m.round < r.round) return;
  r.round = m.round;
  for (std::size_t k = 0; k < m.pose_ids.size(); ++k)
    r.lifted[m.pose_ids[k]] =
        std::vector<double>(m.data.begin() + static_cast<long>(k * width),
                            m.data.begin() + static_cast<long>((k + 1) * width));
}

const Replica* ReplicaStore::find(std::uint32_t a) const {
  auto it = by_agent_.find(a);
  return it == by_agent_.end() ? nullptr : &it->second;
}

PoseBlockMessage replica_block(std::uint32_t self, std::uint32_t round, int d,
                               const std::vector<std::uint32_t>& owned, const Eigen::MatrixXd& Y) {
  PoseBlockMessage m;
  m.round = round;
  m.sender = self;
  m.phase = kReplicaPhase;
  m.rank = static_cast<std::uint32_t>(Y.rows());
  m.dim = static_cast<std::uint32_t>(d);
  m.pose_ids = owned;
  m.data.assign(Y.data(), Y.data() + Y.size());  // column-major: pose after pose
  return m;
}

namespace {

bool contains(const std::vector<std::uint32_t>& v, std::uint32_t x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

std::vector<double> own_column(const TakeoverSource& src, std::uint32_t id) {
  const auto& owned = src.local->owned;
  const auto it = std::lower_bound(owned.begin(), owned.end(), id);
  const Eigen::Index w = src.local->d + 1;
  const auto k = static_cast<Eigen::Index>(it - owned.begin());
  const Eigen::MatrixXd col = src.Y.middleCols(w * k, w);
  return std::vector<double>(col.data(), col.data() + col.size());
}

// Every measurement this source holds: its own problem's and the lost agents' replicas'.
template <class F>
void for_each_held(const TakeoverSource& src, const Reassignment& r, F f) {
  for (std::size_t k = 0; k < src.local->measurements.size(); ++k)
    f(src.local->measurements[k], src.local->measurement_index[k]);
  for (std::uint32_t a : r.lost)
    if (const Replica* rep = src.replicas->find(a))
      for (std::size_t k = 0; k < rep->measurements.size(); ++k)
        f(rep->measurements[k], rep->measurement_index[k]);
}

}  // namespace

TakeoverMessage plan_takeover(const TakeoverSource& src, const Reassignment& r,
                              std::uint32_t recipient) {
  TakeoverMessage out;
  out.sender = src.self;
  out.round = src.round;
  auto gains = [&](std::size_t v) {
    return r.new_owner[v] == recipient && r.old_owner[v] != recipient;
  };
  std::set<std::uint64_t> sent;
  for_each_held(src, r, [&](const Measurement& m, std::uint64_t index) {
    if ((gains(m.i) || gains(m.j)) && sent.insert(index).second) {
      out.measurements.push_back(m);
      out.measurement_index.push_back(index);
    }
  });
  for (std::uint32_t v = 0; v < r.new_owner.size(); ++v) {
    if (!gains(v)) continue;
    std::vector<double> col;
    if (r.old_owner[v] == src.self) {
      col = own_column(src, v);
    } else if (contains(r.lost, r.old_owner[v])) {
      if (const Replica* rep = src.replicas->find(r.old_owner[v])) {
        auto it = rep->lifted.find(v);
        if (it != rep->lifted.end()) col = it->second;
      }
    }
    if (col.empty()) continue;
    out.lifted_ids.push_back(v);
    out.lifted_data.insert(out.lifted_data.end(), col.begin(), col.end());
  }
  return out;
}

AgentLocalData assemble_takeover(const TakeoverSource& src, const Reassignment& r,
                                 const std::vector<TakeoverMessage>& received) {
  const AgentLocalData& old = *src.local;
  const auto me_it = std::find(r.survivors.begin(), r.survivors.end(), src.self);
  if (me_it == r.survivors.end())
    throw std::runtime_error("agent " + std::to_string(src.self) + " is not among the survivors");
  AgentLocalData local;
  local.agent_id = static_cast<std::uint32_t>(me_it - r.survivors.begin());
  local.num_agents = static_cast<std::uint32_t>(r.survivors.size());
  local.d = old.d;
  local.num_poses = old.num_poses;
  local.structure = old.structure;
  local.options = old.options;
  local.owner.resize(r.new_owner.size());
  for (std::size_t v = 0; v < r.new_owner.size(); ++v) {
    const auto it = std::find(r.survivors.begin(), r.survivors.end(), r.new_owner[v]);
    if (it == r.survivors.end())
      throw std::runtime_error("the re-partition gives pose " + std::to_string(v) + " to agent " +
                               std::to_string(r.new_owner[v]) + ", which is not a survivor");
    local.owner[v] = static_cast<std::uint32_t>(it - r.survivors.begin());
    if (r.new_owner[v] == src.self) local.owned.push_back(static_cast<std::uint32_t>(v));
  }
  auto mine = [&](std::size_t v) { return r.new_owner[v] == src.self; };

  // Measurements: own problem, replicas held, received; each once, in file order.
  std::map<std::uint64_t, Measurement> by_index;
  auto take = [&](const Measurement& m, std::uint64_t index) {
    if (mine(m.i) || mine(m.j)) by_index.emplace(index, m);
  };
  for_each_held(src, r, take);
  for (const TakeoverMessage& t : received)
    for (std::size_t k = 0; k < t.measurements.size(); ++k)
      take(t.measurements[k], t.measurement_index[k]);
  for (const auto& [index, m] : by_index) {
    local.measurements.push_back(m);
    local.measurement_index.push_back(index);
  }
  std::size_t expected = 0;
  for (const auto& [i, j] : old.structure) expected += mine(i) || mine(j);
  if (expected != local.measurements.size())
    throw std::runtime_error("agent " + std::to_string(src.self) + " has " +
                             std::to_string(local.measurements.size()) + " of the " +
                             std::to_string(expected) +
                             " measurements touching its poses after the re-partition: the "
                             "missing ones had no surviving replica");

  // Starting point: own current poses, else the newest lifted column offered for the pose.
  const int r_rank = static_cast<int>(src.Y.rows());
  const Eigen::Index w = old.d + 1;
  const std::size_t width = static_cast<std::size_t>(r_rank) * static_cast<std::size_t>(w);
  std::map<std::uint32_t, std::pair<std::uint32_t, std::vector<double>>> offered;  // id -> round
  auto offer = [&](std::uint32_t id, std::uint32_t round, std::vector<double> col) {
    auto it = offered.find(id);
    if (it == offered.end() || round > it->second.first) offered[id] = {round, std::move(col)};
  };
  for (std::uint32_t a : r.lost)
    if (const Replica* rep = src.replicas->find(a))
      for (const auto& [id, col] : rep->lifted)
        if (mine(id)) offer(id, rep->round, col);
  for (const TakeoverMessage& t : received) {
    if (t.lifted_data.size() != t.lifted_ids.size() * width)
      throw std::runtime_error("take-over from agent " + std::to_string(t.sender) +
                               ": lifted poses of the wrong size");
    for (std::size_t k = 0; k < t.lifted_ids.size(); ++k)
      offer(t.lifted_ids[k], t.round,
            std::vector<double>(t.lifted_data.begin() + static_cast<long>(k * width),
                                t.lifted_data.begin() + static_cast<long>((k + 1) * width)));
  }
  local.lifted_start.resize(r_rank, w * static_cast<Eigen::Index>(local.owned.size()));
  for (std::size_t s = 0; s < local.owned.size(); ++s) {
    const std::uint32_t id = local.owned[s];
    std::vector<double> col;
    if (r.old_owner[id] == src.self) {
      col = own_column(src, id);
    } else {
      auto it = offered.find(id);
      if (it == offered.end())
        throw std::runtime_error("pose " + std::to_string(id) + " (agent " +
                                 std::to_string(r.old_owner[id]) + ") reached agent " +
                                 std::to_string(src.self) +
                                 " with no lifted pose: no surviving replica");
      col = it->second.second;
    }
    local.lifted_start.middleCols(w * static_cast<Eigen::Index>(s), w) =
        Eigen::Map<const Eigen::MatrixXd>(col.data(), r_rank, w);
  }
  return local;
}

}  // namespace tessera::agent
