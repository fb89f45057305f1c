#include "runtime/replay_input.hpp"

#include <algorithm>
#include <numeric>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "generate/robot_ranges.hpp"
#include "runtime/robot_file.hpp"

namespace tessera::runtime {

ReplayInput replay_input_from_file(const std::string& path, std::size_t robots) {
  ReplayInput in;
  in.graph = read_g2o(path);
  if (robots == 0 || robots > in.graph.num_poses)
    throw InputError(path, 0,
                     "replay: --robots must be 1.." + std::to_string(in.graph.num_poses) +
                         " (the graph's poses), got " + std::to_string(robots));
  in.robots = robots;
  in.robot_of_pose = robot_of_poses(in.graph.num_poses, robots);
  return in;
}

ReplayInput replay_input_from_robot_files(const std::vector<std::string>& files) {
  ReplayInput in;
  in.robots = files.size();
  std::vector<std::pair<std::uint64_t, Measurement>> measurements;
  std::vector<std::vector<Pose>> initial;
  bool all_initial = true;
  for (std::size_t r = 0; r < files.size(); ++r) {
    const agent::RobotShare share = agent::read_robot_file(files[r], static_cast<std::uint32_t>(r));
    if (r == 0) in.graph.d = share.d;
    if (share.d != in.graph.d)
      throw InputError(files[r], 0,
                       "replay: " + std::to_string(share.d) + "D, robot 0's file is " +
                           std::to_string(in.graph.d) + "D");
    if (share.begin != in.graph.num_poses)
      throw InputError(files[r], 0,
                       "replay: the robot's poses start at " + std::to_string(share.begin) +
                           ", expected " + std::to_string(in.graph.num_poses) +
                           " (the files' ranges must follow each other in name order)");
    in.graph.num_poses = share.end;
    in.robot_of_pose.resize(share.end, r);
    for (std::size_t k = 0; k < share.measurements.size(); ++k)
      measurements.emplace_back(share.measurement_index[k], share.measurements[k]);
    all_initial = all_initial && !share.initial.empty();
    initial.push_back(share.initial);
  }
  for (const auto& [index, m] : measurements)
    if (m.i >= in.graph.num_poses || m.j >= in.graph.num_poses)
      throw InputError("replay: a measurement names pose " + std::to_string(std::max(m.i, m.j)) +
                       ", beyond the robot files' " + std::to_string(in.graph.num_poses) +
                       " poses");
  std::stable_sort(measurements.begin(), measurements.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [index, m] : measurements) in.graph.measurements.push_back(std::move(m));
  if (all_initial)
    for (auto& own : initial)
      in.graph.initial.insert(in.graph.initial.end(), own.begin(), own.end());
  in.graph.source = files.empty() ? std::string() : files.front();
  return in;
}

}  // namespace tessera::runtime
