#pragma once
// A multi-robot trajectory as evaluation sees it: per robot, its poses with an index (the
// pose's number in the robot) and, when known, a timestamp. Estimates and ground truths
// from any source (g2o graphs, TUM files, folders of per-robot TUM files) become this.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace tessera {

struct TrajectoryPose {
  std::uint64_t index = 0;  ///< Number of the pose in its robot (g2o: key index; TUM: order).
  double stamp = 0;         ///< Seconds; meaningful when the robot's trajectory has_stamps.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  ///< 2D poses: rotation about z.
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      ///< 2D poses: z = 0.
};

struct RobotTrajectory {
  std::string name;  ///< Robot name ("" for a single unnamed trajectory, e.g. one TUM file).
  bool has_stamps = false;
  std::vector<TrajectoryPose> poses;  ///< In index (or stamp) order.
};

struct Trajectory {
  int d = 3;  ///< 2 when every pose lies in the plane z = 0 with a rotation about z.
  std::string source;
  std::vector<RobotTrajectory> robots;

  std::size_t num_poses() const {
    std::size_t n = 0;
    for (const auto& r : robots) n += r.poses.size();
    return n;
  }
};

}  // namespace tessera
