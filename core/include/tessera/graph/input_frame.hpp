#pragma once
// Putting a solution into the frame of its input. A pose-graph optimum is only defined up to
// one rigid motion of all poses (the gauge): the relaxation and the rounding return some
// member of that family. Output should overlay the input, so the answer is moved rigidly
// until the anchor pose -- the pose of the file's first FIX line, else pose 0 (the smallest
// id) -- sits exactly at its VERTEX value. The cost does not change.

#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

/// Dense index of the anchor pose: keys.fixed, else 0.
std::size_t anchor_pose(const PoseKeys& keys);

/// Applies the rigid motion T = X_anchor(input) * X_anchor(poses)^-1 to every pose, so the
/// anchor gets its VERTEX value. Does nothing when the graph has no VERTEX poses or `poses`
/// does not have one pose per graph pose.
void move_to_input_frame(const PoseGraph& graph, const PoseKeys& keys, std::vector<Pose>& poses);

}  // namespace tessera
