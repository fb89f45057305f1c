#pragma once
// One TUM trajectory file per robot (what evo_ape and most SLAM evaluation tools read).

#include <string>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

/// Writes DIR/robot_<name>.tum for every robot of `keys` (creating DIR): its poses in
/// id order, one line "timestamp tx ty tz qx qy qz qw" each (2D poses with z = 0). The
/// timestamp is the pose's stamp (keys.stamps) when there are stamps, otherwise the
/// pose's index in its robot; the header comment says which. Returns the paths written.
/// Throws InputError naming the path when a file cannot be written or `poses` does not
/// have one pose per graph pose.
std::vector<std::string> write_robot_trajectories(const PoseGraph& graph, const PoseKeys& keys,
                                                  const std::vector<Pose>& poses,
                                                  const std::string& dir);

/// The header line that marks a TUM file's timestamps as pose indices (readers match such
/// files by index, not by time).
constexpr const char* kTumIndexStampsNote = "# timestamp = pose index (no stamps given)";

}  // namespace tessera
