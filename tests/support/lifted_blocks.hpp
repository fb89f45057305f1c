#pragma once
// A block as the tests of block-level code need it: a random graph whose first half is "the
// block" (its columns of a lifted iterate: gather_pose_columns, <tessera/problem/lifting.hpp>).

#include <cstddef>
#include <cstdint>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera::test {

/// A random graph (random_pose_graph: 40 poses, 30 loop closures, default noise) and its
/// first 20 poses as the block (`owned`, ascending); the other poses are its neighbours.
struct HalfBlock {
  PoseGraph graph;
  std::vector<std::size_t> owned;
};
HalfBlock half_block(int d, std::uint64_t seed);

}  // namespace tessera::test
