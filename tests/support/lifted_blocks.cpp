#include "lifted_blocks.hpp"

#include "random_graph.hpp"

namespace tessera::test {

Eigen::MatrixXd pose_columns(const Eigen::MatrixXd& X, int d,
                             const std::vector<std::size_t>& which) {
  const Eigen::Index w = d + 1;
  Eigen::MatrixXd out(X.rows(), w * static_cast<Eigen::Index>(which.size()));
  for (std::size_t s = 0; s < which.size(); ++s)
    out.middleCols(w * static_cast<Eigen::Index>(s), w) =
        X.middleCols(w * static_cast<Eigen::Index>(which[s]), w);
  return out;
}

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
