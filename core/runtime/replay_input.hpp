#pragma once
// What `tessera replay` plays: one multi-robot graph and the robot of every pose, from a
// whole g2o file (robot r of R owns the contiguous ids [r n / R, (r + 1) n / R), as
// `generate` numbers them) or from per-robot files (`generate --split`; robot_file.hpp),
// whose ranges say who owns what.

#include <cstddef>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera::runtime {

struct ReplayInput {
  PoseGraph graph;                         ///< Global ids; measurements in input order.
  std::vector<std::size_t> robot_of_pose;  ///< Robot of every pose id.
  std::size_t robots = 0;
};

/// Whole file `path` shared among `robots` robots. Throws InputError (naming the file) when
/// robots is 0 or exceeds the poses.
ReplayInput replay_input_from_file(const std::string& path, std::size_t robots);

/// Robot files, robot r = files[r]: their ranges must tile 0..n-1 in order. Measurements are
/// ordered by their `# tessera-measurement-index` (the whole file's order). Throws InputError
/// naming the file that does not fit.
ReplayInput replay_input_from_robot_files(const std::vector<std::string>& files);

}  // namespace tessera::runtime
