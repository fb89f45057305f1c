#pragma once
// What one robot brings to a run and how its data moves to the agents that own it after
// the partition (no DDS here: pure bookkeeping, shared by the agent executable and tests).

#include <cstdint>
#include <tessera/graph/pose_graph.hpp>
#include <utility>
#include <vector>

#include "runtime/round_loop.hpp"

namespace tessera::agent {

/// Robot `robot`'s share of a whole multi-robot graph: its contiguous poses
/// [begin, end) = [robot n / N, (robot + 1) n / N), the measurements whose first endpoint i
/// lies there (each measurement belongs to exactly one robot), and the initial poses of its
/// range. Measurement values never leave the agents.
struct RobotShare {
  int d = 0;
  std::size_t num_poses = 0;
  std::uint32_t begin = 0, end = 0;
  std::vector<Measurement> measurements;
  std::vector<std::uint64_t> measurement_index;  ///< Position in the file.
  std::vector<Pose> initial;                     ///< end - begin poses, or empty.
  /// A robust run's second candidate start of [begin, end) (the known inliers'
  /// initialization, runtime/known_inlier_start.hpp), or empty.
  std::vector<Pose> known_initial;
  /// measurement_index values of the share's measurements flagged as known inliers (a robot
  /// file's '# tessera-known-inliers' line, from a dpgo CSV file), ascending.
  std::vector<std::uint64_t> known_inlier_index;
};

/// Throws InputError (naming graph.source) when N > n.
RobotShare robot_share(const PoseGraph& graph, std::uint32_t robot, std::uint32_t num_robots);

/// What `share` must send to agent `recipient` under `owner`: the measurements with an
/// endpoint owned by `recipient` (which the recipient does not hold yet) and the initial
/// poses of the share that `recipient` owns.
struct HandoffPlan {
  std::vector<const Measurement*> measurements;
  std::vector<std::uint64_t> measurement_index;
  std::vector<std::pair<std::uint32_t, const Pose*>> poses;
  std::vector<std::pair<std::uint32_t, const Pose*>> known_poses;  ///< Of share.known_initial.
};
HandoffPlan plan_handoff(const RobotShare& share, const std::vector<std::uint32_t>& owner,
                         std::uint32_t recipient);

/// A received hand-off (decoded).
struct ReceivedHandoff {
  std::uint32_t sender = 0;
  std::vector<Measurement> measurements;
  std::vector<std::uint64_t> measurement_index;
  std::vector<std::pair<std::uint32_t, Pose>> poses;
  std::vector<std::pair<std::uint32_t, Pose>> known_poses;
};

/// The local problem of agent `self` after the hand-off: its owned poses, every
/// measurement touching them (own share's and received, sorted by file position, no
/// duplicates) and their initial poses (and known_initial when the share has it). Throws
/// std::runtime_error naming what is inconsistent (a pose never handed over, a measurement received
/// twice, ...).
AgentLocalData assemble_local(const RobotShare& share, const std::vector<std::uint32_t>& owner,
                              std::uint32_t self, std::uint32_t num_agents,
                              std::vector<ReceivedHandoff> received, const RunOptions& options);

}  // namespace tessera::agent
