#include <deque>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/util/input_error.hpp>

#include "generate/robot_ranges.hpp"

namespace tessera {

const char* init_name(DistributedInit init) {
  if (init == DistributedInit::kFile) return "file";
  return init == DistributedInit::kChordal ? "chordal" : "distributed";
}

DistributedInit parse_init(const std::string& name) {
  if (name == "chordal") return DistributedInit::kChordal;
  if (name == "distributed") return DistributedInit::kDistributed;
  if (name == "file") return DistributedInit::kFile;
  throw InputError("initialization '" + name + "' is not one of chordal, distributed, file");
}

namespace {

Pose compose(const Pose& a, const Pose& b) {
  return {a.R * b.R, a.R * b.t + a.t};
}
Pose inverse(const Pose& a) {
  return {a.R.transpose(), -(a.R.transpose() * a.t)};
}

}  // namespace

Pose place_in_frame(const Pose& frame, const Pose& local) {
  return compose(frame, local);
}

RobotUnits robot_units(int d, std::size_t begin, std::size_t end,
                       const std::vector<Measurement>& measurements, const std::string& source) {
  const std::size_t n = end - begin;
  auto inside = [&](const Measurement& m) {
    return m.i >= begin && m.i < end && m.j >= begin && m.j < end;
  };
  std::vector<std::pair<std::size_t, std::size_t>> joined;  // the robot's own, as local ids
  for (const auto& m : measurements)
    if (inside(m)) joined.emplace_back(m.i - begin, m.j - begin);
  // Units numbered by their smallest pose (connected_components' labels); members ascending.
  const std::vector<std::size_t> unit = connected_components(n, joined);
  std::vector<std::size_t> local(n);
  RobotUnits out;
  for (std::size_t i = 0; i < n; ++i) {
    if (unit[i] == out.members.size()) out.members.emplace_back();
    local[i] = out.members[unit[i]].size();
    out.members[unit[i]].push_back(begin + i);
  }
  std::vector<PoseGraph> sub(out.members.size());
  for (std::size_t u = 0; u < sub.size(); ++u) {
    sub[u].d = d;
    sub[u].num_poses = out.members[u].size();
    sub[u].source = source;
  }
  for (const auto& m : measurements) {
    if (!inside(m)) continue;
    Measurement c = m;
    c.i = local[m.i - begin];
    c.j = local[m.j - begin];
    sub[unit[m.i - begin]].measurements.push_back(std::move(c));
  }
  out.poses.resize(sub.size());
  for (std::size_t u = 0; u < sub.size(); ++u)
    out.poses[u] = out.members[u].size() == 1 ? std::vector<Pose>{Pose::identity(d)}
                                              : chordal_initialization(sub[u]);
  return out;
}

std::vector<Pose> align_units(int d, std::size_t num_units,
                              const std::vector<Measurement>& crossing,
                              const std::map<std::size_t, UnitPose>& endpoint) {
  auto at = [&](std::size_t id) -> const UnitPose& {
    auto it = endpoint.find(id);
    if (it == endpoint.end() || it->second.unit >= num_units)
      throw InputError("distributed initialization: no unit pose for pose " + std::to_string(id) +
                       " at the end of an inter-robot measurement");
    return it->second;
  };
  std::vector<std::vector<std::size_t>> touching(num_units);
  for (std::size_t k = 0; k < crossing.size(); ++k) {
    touching[at(crossing[k].i).unit].push_back(k);
    touching[at(crossing[k].j).unit].push_back(k);
  }
  std::vector<Pose> frame(num_units);
  std::vector<bool> aligned(num_units, false);
  for (std::size_t start = 0; start < num_units; ++start) {
    if (aligned[start]) continue;  // a new tree per connected component of the whole graph
    aligned[start] = true;
    frame[start] = Pose::identity(d);
    std::deque<std::size_t> queue{start};
    while (!queue.empty()) {
      const std::size_t a = queue.front();
      queue.pop_front();
      for (std::size_t k : touching[a]) {
        const Measurement& m = crossing[k];
        const bool forward = at(m.i).unit == a;
        const UnitPose& from = forward ? at(m.i) : at(m.j);
        const UnitPose& to = forward ? at(m.j) : at(m.i);
        const std::size_t b = to.unit;
        if (aligned[b]) continue;
        const Pose z{m.R, m.t};
        const Pose g_from = compose(frame[a], from.local);
        const Pose g_to = compose(g_from, forward ? z : inverse(z));
        frame[b] = compose(g_to, inverse(to.local));
        aligned[b] = true;
        queue.push_back(b);
      }
    }
  }
  return frame;
}

std::vector<Pose> distributed_initialization(const PoseGraph& graph, int robots) {
  const std::size_t n = graph.num_poses;
  if (robots < 1 || static_cast<std::size_t>(robots) > n)
    throw InputError("distributed initialization: robots must be in 1.." + std::to_string(n));
  const std::size_t R = static_cast<std::size_t>(robots);
  const std::vector<std::size_t> robot = robot_of_poses(n, R);
  // Each robot's measurements: those recorded from its poses (first endpoint).
  std::vector<std::vector<Measurement>> own(R);
  std::vector<Measurement> crossing;
  for (const auto& m : graph.measurements) {
    own[robot[m.i]].push_back(m);
    if (robot[m.i] != robot[m.j]) crossing.push_back(m);
  }
  std::vector<RobotUnits> units(R);
  std::map<std::size_t, UnitPose> endpoint;
  std::vector<std::size_t> offset(R + 1, 0);
  for (std::size_t r = 0; r < R; ++r) {
    units[r] =
        robot_units(graph.d, robot_begin(r, n, R), robot_begin(r + 1, n, R), own[r], graph.source);
    offset[r + 1] = offset[r] + units[r].members.size();
  }
  std::vector<std::pair<std::size_t, std::size_t>> slot(n);  // (unit, member) of every pose
  for (std::size_t r = 0; r < R; ++r)
    for (std::size_t u = 0; u < units[r].members.size(); ++u)
      for (std::size_t k = 0; k < units[r].members[u].size(); ++k)
        slot[units[r].members[u][k]] = {u, k};
  for (const auto& m : crossing)
    for (std::size_t id : {m.i, m.j}) {
      const auto [u, k] = slot[id];
      endpoint[id] = {offset[robot[id]] + u, units[robot[id]].poses[u][k]};
    }
  const std::vector<Pose> frame = align_units(graph.d, offset[R], crossing, endpoint);
  std::vector<Pose> poses(n);
  for (std::size_t r = 0; r < R; ++r)
    for (std::size_t u = 0; u < units[r].members.size(); ++u)
      for (std::size_t k = 0; k < units[r].members[u].size(); ++k)
        poses[units[r].members[u][k]] = place_in_frame(frame[offset[r] + u], units[r].poses[u][k]);
  return poses;
}

std::vector<Pose> initial_poses(const PoseGraph& graph, DistributedInit init, int robots) {
  if (init == DistributedInit::kChordal) return chordal_initialization(graph);
  if (init == DistributedInit::kFile) {
    if (!graph.has_initial())
      throw InputError(graph.source, 0, "initialization 'file' needs a VERTEX line for every pose");
    return graph.initial;
  }
  return distributed_initialization(graph, robots);
}

}  // namespace tessera
