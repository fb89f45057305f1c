#pragma once
// The pose part of one TUM trajectory line, shared by the single-file and per-robot writers.

#include <string>
#include <tessera/graph/pose.hpp>

namespace tessera {

/// Appends " tx ty tz qx qy qz qw\n" for `p` after a timestamp the caller has written: a 2D
/// pose gets z = 0 and its rotation about z, the quaternion is unit with qw >= 0.
void append_tum_pose(std::string& out, const Pose& p);

}  // namespace tessera
