#pragma once
// Timestamps for the poses of a graph, from a text file given with --stamps. Two layouts
// (one per file, by its first data line):
//  - "id stamp": the pose with that input id (keys.id) gets that stamp; every pose
//    needs exactly one line.
//  - TUM "stamp tx ty tz qx qy qz qw": the k-th line's stamp goes to the k-th pose in id
//    order; there must be exactly one line per pose.
// Blank lines and '#' comments are skipped. Stamps are seconds (any finite number).

#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

/// Reads the stamps of `graph`'s poses from `path` (one per pose, in dense order). Throws
/// InputError naming the file and line for a malformed line, an unknown or repeated id, a
/// line too many, and the file (line 0) when poses are left without a stamp.
std::vector<double> read_stamps_file(const std::string& path, const PoseGraph& graph,
                                     const PoseKeys& keys);

/// Writes "id stamp" lines for every pose with keys.stamps.
void write_stamps_file(const PoseKeys& keys, std::size_t num_poses, const std::string& path);

}  // namespace tessera
