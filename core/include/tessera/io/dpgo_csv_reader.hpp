#pragma once
// Reading the multi-robot measurement CSV of dpgo's ROS wrapper (docs/file-formats.md,
// "dpgo measurement CSV"): header
//   robot_src,pose_src,robot_dst,pose_dst,qx,qy,qz,qw,tx,ty,tz,kappa,tau,is_known_inlier,weight
// then one 3D measurement per row, poses named (robot, index within the robot). Either one
// file, or a folder holding robot<k>/measurements.csv for k = 0, 1, ... (each robot's own
// file; a measurement listed by both robots it joins is kept once).

#include <cstddef>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct DpgoCsvGraph {
  /// Global ids: robot r's pose k is offset(r) + k, offset(r) = sum over robots q < r of
  /// (1 + the largest index of q seen). Measurements in file order (files by robot number).
  /// Quaternions are normalised; kappa and tau are the rotation and translation weights as
  /// written. No initial guess (the file has none).
  PoseGraph graph;
  std::vector<bool> known_inlier;  ///< is_known_inlier of each measurement.
  std::vector<int> robot_of;       ///< Robot of each global pose id.
  std::size_t duplicates = 0;      ///< Rows skipped because the same pair was read already.
};

/// True when `path` is a .csv file or a folder with robot0/measurements.csv.
bool is_dpgo_csv(const std::string& path);

/// Reads `path` (file or folder, see above). Throws InputError "file:line: what" for a bad
/// header, a wrong number of fields, a field that is not a number (or not 0/1 for
/// is_known_inlier), a negative index, a zero quaternion, a weight that is not finite and
/// > 0, a measurement from a pose to itself, or a file that cannot be read; and when the
/// measurements do not connect every pose.
DpgoCsvGraph read_dpgo_csv(const std::string& path);

}  // namespace tessera
