#include "distributed/distributed_initialization.hpp"

#include <deque>

#include "partition/sequential_partition.hpp"
#include "solvers/chordal_initialization.hpp"
#include "util/input_error.hpp"

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

// Union-find over poses, joining only measurements inside one robot.
std::size_t find(std::vector<std::size_t>& parent, std::size_t x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

std::vector<Pose> distributed_initialization(const PoseGraph& graph, int robots) {
  const std::size_t n = graph.num_poses;
  if (robots < 1 || static_cast<std::size_t>(robots) > n)
    throw InputError("distributed initialization: robots must be in 1.." + std::to_string(n));
  const std::vector<int> robot = sequential_partition(n, robots);
  // Units: connected components of each robot's own measurements.
  std::vector<std::size_t> parent(n);
  for (std::size_t i = 0; i < n; ++i) parent[i] = i;
  for (const auto& m : graph.measurements)
    if (robot[m.i] == robot[m.j]) parent[find(parent, m.i)] = find(parent, m.j);
  std::vector<std::size_t> unit(n), root_unit(n, n), local(n);
  std::vector<std::vector<std::size_t>> members;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t r = find(parent, i);
    if (root_unit[r] == n) {
      root_unit[r] = members.size();
      members.emplace_back();
    }
    unit[i] = root_unit[r];
    local[i] = members[unit[i]].size();
    members[unit[i]].push_back(i);
  }
  // Each unit's trajectory in its own frame (what each robot can compute alone).
  std::vector<PoseGraph> sub(members.size());
  for (std::size_t u = 0; u < members.size(); ++u) {
    sub[u].d = graph.d;
    sub[u].num_poses = members[u].size();
    sub[u].source = graph.source;
  }
  std::vector<std::vector<std::size_t>> crossing(members.size());
  for (std::size_t k = 0; k < graph.measurements.size(); ++k) {
    const auto& m = graph.measurements[k];
    if (unit[m.i] == unit[m.j]) {
      Measurement c = m;
      c.i = local[m.i];
      c.j = local[m.j];
      sub[unit[m.i]].measurements.push_back(std::move(c));
    } else {
      crossing[unit[m.i]].push_back(k);
      crossing[unit[m.j]].push_back(k);
    }
  }
  std::vector<std::vector<Pose>> local_poses(members.size());
  for (std::size_t u = 0; u < members.size(); ++u)
    local_poses[u] = members[u].size() == 1 ? std::vector<Pose>{Pose::identity(graph.d)}
                                            : chordal_initialization(sub[u]);
  // Frames: breadth-first over units, each new unit aligned by the first measurement reaching it.
  std::vector<Pose> frame(members.size(), Pose::identity(graph.d));
  std::vector<bool> aligned(members.size(), false);
  for (std::size_t start = 0; start < members.size(); ++start) {
    if (aligned[start]) continue;  // a new tree per connected component of the whole graph
    aligned[start] = true;
    std::deque<std::size_t> queue{start};
    while (!queue.empty()) {
      const std::size_t a = queue.front();
      queue.pop_front();
      for (std::size_t k : crossing[a]) {
        const auto& m = graph.measurements[k];
        const bool forward = unit[m.i] == a;
        const std::size_t b = forward ? unit[m.j] : unit[m.i];
        if (aligned[b]) continue;
        const Pose z{m.R, m.t};
        const std::size_t from = forward ? m.i : m.j, to = forward ? m.j : m.i;
        const Pose g_from = compose(frame[a], local_poses[a][local[from]]);
        const Pose g_to = compose(g_from, forward ? z : inverse(z));
        frame[b] = compose(g_to, inverse(local_poses[b][local[to]]));
        aligned[b] = true;
        queue.push_back(b);
      }
    }
  }
  std::vector<Pose> poses(n);
  for (std::size_t i = 0; i < n; ++i)
    poses[i] = compose(frame[unit[i]], local_poses[unit[i]][local[i]]);
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
