#pragma once
// Cutting a block out of a whole lifted graph, as the tests of block-level code need it:
// the columns of some poses, and a random graph whose first half is "the block".

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera::test {

/// The columns of the poses `which` of the lifted iterate X (r x (d+1)n), in that order:
/// what an agent holding those poses (its block, or its copies of neighbours) starts from.
/// Each pose has d + 1 columns; every id in `which` must be < n.
Eigen::MatrixXd pose_columns(const Eigen::MatrixXd& X, int d,
                             const std::vector<std::size_t>& which);

/// A random graph (random_pose_graph: 40 poses, 30 loop closures, default noise) and its
/// first 20 poses as the block (`owned`, ascending); the other poses are its neighbours.
struct HalfBlock {
  PoseGraph graph;
  std::vector<std::size_t> owned;
};
HalfBlock half_block(int d, std::uint64_t seed);

}  // namespace tessera::test
