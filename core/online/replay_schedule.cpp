#include <algorithm>
#include <cmath>
#include <map>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

void ReplayOptions::validate() const {
  auto fail = [](const std::string& field, const char* why) {
    throw InputError("ReplayOptions." + field + " " + why);
  };
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate", "must be > 0 (poses per second)");
  if (!(speedup > 0) || !std::isfinite(speedup)) fail("speedup", "must be > 0");
  for (std::size_t r = 0; r < start_s.size(); ++r)
    if (!(start_s[r] >= 0) || !std::isfinite(start_s[r]))
      fail("start_s[" + std::to_string(r) + "]", "must be >= 0 seconds");
}

ReplayPlan plan_replay(const PoseGraph& graph, const std::vector<std::size_t>& robot_of_pose,
                       const ReplayOptions& options) {
  options.validate();
  const std::size_t n = graph.num_poses;
  if (robot_of_pose.size() != n)
    throw InputError(graph.source, 0,
                     "replay: " + std::to_string(robot_of_pose.size()) + " robot ids for " +
                         std::to_string(n) + " poses");
  std::size_t robots = 0;
  for (std::size_t r : robot_of_pose) robots = std::max(robots, r + 1);
  ReplayPlan plan;
  plan.original_id.resize(robots);
  std::vector<std::uint64_t> index(n);
  for (std::size_t k = 0; k < n; ++k) {
    auto& mine = plan.original_id[robot_of_pose[k]];
    index[k] = mine.size();
    mine.push_back(k);
  }
  for (std::size_t r = 0; r < robots; ++r)
    if (plan.original_id[r].empty())
      throw InputError(graph.source, 0, "replay: robot " + std::to_string(r) + " has no pose");

  // Tick of a pose = its index along its robot; time = start + tick / rate.
  auto start = [&](std::size_t r) { return r < options.start_s.size() ? options.start_s[r] : 0.0; };
  auto time_of = [&](std::size_t k) {
    return (start(robot_of_pose[k]) + static_cast<double>(index[k]) / options.rate) /
           options.speedup;
  };
  auto key = [&](std::size_t k) {
    return PoseKey{static_cast<std::uint32_t>(robot_of_pose[k]), index[k]};
  };
  // One batch per pose: the pose, then the measurements it completes (published by the robot
  // whose pose came last; ties go to the later id, which publishes after the earlier one).
  std::vector<StreamBatch> by_pose(n);
  for (std::size_t k = 0; k < n; ++k) {
    StreamBatch& b = by_pose[k];
    b.robot = key(k).robot;
    b.sequence = index[k];
    b.stamp = time_of(k);
    Pose guess = graph.has_initial() ? graph.initial[k] : Pose::identity(graph.d);
    b.poses.push_back(StreamPose{key(k), b.stamp, std::move(guess)});
  }
  for (const Measurement& m : graph.measurements) {
    const double ti = time_of(m.i), tj = time_of(m.j);
    const std::size_t last = tj > ti || (tj == ti && m.j > m.i) ? m.j : m.i;
    StreamMeasurement s;
    s.from = key(m.i);
    s.to = key(m.j);
    const bool same = robot_of_pose[m.i] == robot_of_pose[m.j];
    const bool consecutive = index[m.i] + 1 == index[m.j] || index[m.j] + 1 == index[m.i];
    s.kind = !same         ? MeasurementKind::kInterLoop
             : consecutive ? MeasurementKind::kOdometry
                           : MeasurementKind::kIntraLoop;
    s.stamp = by_pose[last].stamp;
    s.relative = Pose{m.R, m.t};
    s.kappa = m.kappa;
    s.tau = m.tau;
    by_pose[last].measurements.push_back(std::move(s));
    ++plan.measurements;
  }
  // Odometry first in each batch: the receiver composes new poses along it.
  for (auto& b : by_pose)
    std::stable_sort(b.measurements.begin(), b.measurements.end(),
                     [](const StreamMeasurement& a, const StreamMeasurement& c) {
                       return a.kind == MeasurementKind::kOdometry &&
                              c.kind != MeasurementKind::kOdometry;
                     });
  plan.batches = std::move(by_pose);
  std::stable_sort(plan.batches.begin(), plan.batches.end(),
                   [](const StreamBatch& a, const StreamBatch& b) {
                     return a.stamp != b.stamp ? a.stamp < b.stamp : a.robot < b.robot;
                   });
  plan.duration_s = plan.batches.empty() ? 0.0 : plan.batches.back().stamp;
  return plan;
}

}  // namespace tessera
