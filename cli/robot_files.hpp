#pragma once
// `tessera generate --split DIR`: one g2o file per robot, in the convention of
// core/runtime/robot_file.hpp (docs/dds-runtime.md, "One file per robot"): robot r's file holds the
// header lines, the VERTEX lines of its poses [r n / R, (r + 1) n / R) and the EDGE lines of
// the measurements it recorded (first endpoint among its poses), copied byte for byte from
// the whole graph's g2o text so every value parses to the same double.

#include <cstddef>
#include <string>
#include <vector>

namespace tessera::cli {

/// Splits the g2o file `whole` (n poses, global ids) among `robots` robots into
/// DIR/robot<r>.g2o (r zero-padded so names sort in robot order; DIR is created if missing).
/// Returns the paths written. Throws InputError/runtime_error naming the file on failure.
std::vector<std::string> write_robot_files(const std::string& whole, std::size_t num_poses,
                                           std::size_t robots, const std::string& dir);

/// Same with the robot of every pose given (`robot_of`, n entries, each robot's ids
/// contiguous and robots in id order, e.g. a dpgo CSV file's robots). `known_inlier`: empty or
/// one flag per EDGE line of `whole`; the flagged ones go to each robot file's
/// '# tessera-known-inliers' line.
std::vector<std::string> write_robot_files(const std::string& whole,
                                           const std::vector<std::size_t>& robot_of,
                                           std::size_t robots, const std::string& dir,
                                           const std::vector<bool>& known_inlier = {});

}  // namespace tessera::cli

namespace tessera::cli {

/// The per-robot files named by `graph` for `tessera launch`: the *.g2o files of a folder
/// (sorted by name: robot 0 first), or a comma-separated list; empty when `graph` is one
/// file (the whole graph). Throws InputError for a folder without .g2o files.
std::vector<std::string> robot_files_of(const std::string& graph);

}  // namespace tessera::cli
