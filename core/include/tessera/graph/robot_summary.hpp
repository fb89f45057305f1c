#pragma once
// How a multi-robot graph divides among its robots (its keys): poses per robot and its
// measurements by kind. Odometry joins consecutive poses (indices k, k+1) of one robot;
// every other measurement is a loop closure, intra-robot (both poses of one robot) or
// inter-robot.

#include <cstddef>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

struct RobotCounts {
  std::string name;
  std::size_t poses = 0;
  std::size_t odometry = 0;        ///< Odometry measurements inside the robot.
  std::size_t intra_closures = 0;  ///< Loop closures between two of its poses.
  std::size_t inter_closures = 0;  ///< Loop closures between one of its poses and another robot's.
};

struct RobotSummary {
  std::vector<RobotCounts> robots;  ///< In robot order (keys.robot_names).
  std::size_t odometry = 0;
  std::size_t intra_closures = 0;
  std::size_t inter_closures = 0;  ///< Each counted once (it appears in two robots' counts).
};

RobotSummary summarize_robots(const PoseGraph& graph, const PoseKeys& keys);

}  // namespace tessera
