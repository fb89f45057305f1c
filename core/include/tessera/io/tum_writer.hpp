#pragma once
// Writing trajectories in the TUM RGB-D text format (used by evo and most SLAM tools).

#include <string>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

/// Writes one line "timestamp tx ty tz qx qy qz qw" per pose, timestamp = pose index, unit
/// quaternion with qw >= 0. 2D poses are written in the plane z = 0 with their rotation
/// about z. Numbers are in shortest round-trip form. Throws InputError naming `path` when
/// the file cannot be written or a pose is not 2D or 3D.
void write_tum(const std::vector<Pose>& poses, const std::string& path);

/// Same, with the input's names as timestamps: the pose's stamp when keys.stamps has one per
/// pose, else its id keys.id(k) (an integer, so GTSAM keys stay exact).
void write_tum(const std::vector<Pose>& poses, const PoseKeys& keys, const std::string& path);

}  // namespace tessera
