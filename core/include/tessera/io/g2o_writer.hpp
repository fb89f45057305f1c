#pragma once
// Writing pose graphs as g2o text (the format read by read_g2o and by SE-Sync, g2o, GTSAM).

#include <string>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

/// Writes `graph` to `path`: one VERTEX line per pose of `poses` (ids 0..n-1; none when
/// `poses` is empty), then one EDGE line per measurement in graph order. 2D graphs use
/// VERTEX_SE2 / EDGE_SE2, 3D graphs VERTEX_SE3:QUAT / EDGE_SE3:QUAT (unit quaternion with
/// qw >= 0). Information matrices are information_from_weights(d, kappa, tau), i.e.
/// diag(tau, tau, kappa) in 2D and diag(tau I3, 2 kappa I3) in 3D, so reading the file back
/// gives the same weights. Numbers are written in shortest round-trip form: reading the
/// file back reproduces translations bit for bit, and rotations and weights to a few ulps
/// (rotations go through a quaternion or an angle; 3D weights through the trace formula).
/// Throws InputError naming `path` when the file cannot be written, and when `poses` is
/// neither empty nor of size graph.num_poses, or the graph's dimension is not 2 or 3.
void write_g2o(const PoseGraph& graph, const std::vector<Pose>& poses, const std::string& path);

/// Same, with the file's ids keys.id(k) instead of 0..n-1 (keys.ids empty or one per pose),
/// and a last line "FIX id" when keys.fixed is set and there are VERTEX lines.
void write_g2o(const PoseGraph& graph, const PoseKeys& keys, const std::vector<Pose>& poses,
               const std::string& path);

/// Same, with the VERTEX lines taken from graph.initial (none when it is empty).
void write_g2o(const PoseGraph& graph, const std::string& path);

}  // namespace tessera
