#pragma once
// Reading trajectories for evaluation and plots (eval/trajectory.hpp) from:
//  - a g2o or TORO graph with VERTEX lines (robots from its keys, index = key index);
//  - a TUM file "timestamp tx ty tz qx qy qz qw" (one unnamed robot);
//  - a folder of TUM files, one robot each (robot_<name>.tum as --tum-dir writes them).
// A TUM file whose header holds kTumIndexStampsNote has pose indices for timestamps;
// otherwise its timestamps are stamps and its poses are numbered in file order.

#include <optional>
#include <string>
#include <tessera/eval/trajectory.hpp>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

struct TrajectoryReadOptions {
  std::optional<KeyScheme> keys;  ///< For graph files: as G2oReadOptions::keys.
  std::string stamps;             ///< For graph files: a --stamps file (read_stamps_file).
};

/// The poses (one per graph pose) of a graph as a trajectory, robots from `keys`.
Trajectory trajectory_from_graph(const PoseGraph& graph, const PoseKeys& keys,
                                 const std::vector<Pose>& poses);

/// Reads a graph file, a TUM file or a folder of TUM files (see above). Throws InputError
/// naming the file and line for a malformed line, and the file for a graph without VERTEX
/// lines or a folder without .tum files.
Trajectory read_trajectory(const std::string& path, const TrajectoryReadOptions& options = {});

/// Reads one TUM file as a trajectory of one robot called `robot`.
Trajectory read_tum_trajectory(const std::string& path, const std::string& robot = "");

}  // namespace tessera
