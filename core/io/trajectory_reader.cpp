#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/robot_trajectories.hpp>
#include <tessera/io/stamps_reader.hpp>
#include <tessera/io/trajectory_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "io/number_token.hpp"
#include "io/rotation_text.hpp"

namespace tessera {
namespace {

bool planar(const TrajectoryPose& p) {
  return p.t.z() == 0 && std::abs(p.R(2, 2) - 1) < 1e-12;
}

void set_dimension(Trajectory& t) {
  bool flat = true;
  for (const auto& r : t.robots)
    for (const auto& p : r.poses) flat = flat && planar(p);
  t.d = flat ? 2 : 3;
}

// A graph file starts (after blanks and comments) with one of these tags.
bool looks_like_graph(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag) || tag[0] == '#') continue;
    return tag.rfind("VERTEX", 0) == 0 || tag.rfind("EDGE", 0) == 0 || tag == "FIX";
  }
  return false;
}

}  // namespace

Trajectory trajectory_from_graph(const PoseGraph& graph, const PoseKeys& keys,
                                 const std::vector<Pose>& poses) {
  Trajectory t;
  t.d = graph.d;
  t.source = graph.source;
  t.robots.resize(keys.num_robots());
  const bool stamped = keys.stamps.size() == graph.num_poses && graph.num_poses > 0;
  for (std::size_t r = 0; r < t.robots.size(); ++r) {
    t.robots[r].name = keys.robot_name(r);
    t.robots[r].has_stamps = stamped;
  }
  for (std::size_t k = 0; k < graph.num_poses && k < poses.size(); ++k) {
    TrajectoryPose p;
    p.index = keys.index_in_robot(k);
    p.stamp = stamped ? keys.stamps[k] : 0.0;
    p.R.topLeftCorner(graph.d, graph.d) = poses[k].R;
    p.t.head(graph.d) = poses[k].t;
    t.robots[keys.robot_of(k)].poses.push_back(p);
  }
  return t;
}

Trajectory read_tum_trajectory(const std::string& path, const std::string& robot) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "cannot open the trajectory file");
  Trajectory t;
  t.source = path;
  RobotTrajectory r;
  r.name = robot;
  r.has_stamps = true;
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.rfind(kTumIndexStampsNote, 0) == 0) r.has_stamps = false;
    std::istringstream ls(line);
    std::vector<std::string> tok;
    for (std::string s; ls >> s;) tok.push_back(s);
    if (tok.empty() || tok[0][0] == '#') continue;
    if (tok.size() != 8)
      throw InputError(path, number,
                       "a TUM line has 8 values (timestamp tx ty tz qx qy qz qw), found " +
                           std::to_string(tok.size()));
    double v[8];
    for (int k = 0; k < 8; ++k)
      if (!parse_number(tok[k], v[k]) || !std::isfinite(v[k]))
        throw InputError(path, number,
                         "value " + std::to_string(k + 1) + " " + quoted_token(tok[k]) +
                             " is not a finite number");
    const double norm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
    if (!(norm > 1e-6)) throw InputError(path, number, "zero quaternion: not a rotation");
    TrajectoryPose p;
    p.stamp = v[0];
    p.index = static_cast<std::uint64_t>(r.poses.size());
    p.t << v[1], v[2], v[3];
    p.R = rotation_from_quaternion(v[4] / norm, v[5] / norm, v[6] / norm, v[7] / norm);
    r.poses.push_back(p);
  }
  if (!r.has_stamps)  // the timestamps are the poses' indices
    for (auto& p : r.poses) p.index = static_cast<std::uint64_t>(std::llround(p.stamp));
  if (r.poses.empty()) throw InputError(path, 0, "no poses (no TUM lines)");
  t.robots.push_back(std::move(r));
  set_dimension(t);
  return t;
}

Trajectory read_trajectory(const std::string& path, const TrajectoryReadOptions& options) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(path, ec))
      if (e.path().extension() == ".tum") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    if (files.empty()) throw InputError(path, 0, "a trajectory folder needs .tum files");
    Trajectory t;
    t.source = path;
    for (const auto& f : files) {
      std::string name = f.stem().string();
      if (name.rfind("robot_", 0) == 0) name = name.substr(6);
      Trajectory one = read_tum_trajectory(f.string(), name);
      t.robots.push_back(std::move(one.robots.front()));
    }
    set_dimension(t);
    return t;
  }
  if (!looks_like_graph(path)) return read_tum_trajectory(path);
  G2oReadOptions read;
  read.keys = options.keys;
  read.allow_disconnected = true;  // (a trajectory needs no measurements between its poses)
  G2oReadResult r = read_g2o_file(path, read);
  if (!r.graph.has_initial())
    throw InputError(path, 0, "has no VERTEX lines: no trajectory to evaluate");
  if (!options.stamps.empty()) r.keys.stamps = read_stamps_file(options.stamps, r.graph, r.keys);
  return trajectory_from_graph(r.graph, r.keys, r.graph.initial);
}

}  // namespace tessera
