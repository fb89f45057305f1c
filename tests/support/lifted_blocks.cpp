#include "lifted_blocks.hpp"

#include "random_graph.hpp"

namespace tessera::test {

HalfBlock half_block(int d, std::uint64_t seed) {
  RandomGraphSpec spec;
  spec.d = d;
  spec.poses = 40;
  spec.loop_closures = 30;
  spec.seed = seed;
  HalfBlock b;
  b.graph = random_pose_graph(spec);
  for (std::size_t i = 0; i < spec.poses / 2; ++i) b.owned.push_back(i);
  return b;
}

}  // namespace tessera::test
