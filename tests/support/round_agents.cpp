#include "round_agents.hpp"

#include <Eigen/Core>
#include <tessera/problem/lifting.hpp>

namespace tessera::test {

AgentsOfRun::AgentsOfRun(const PoseGraph& g, int N, const DistributedOptions& opt) : graph(g) {
  std::vector<int> assignment(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i)
    assignment[i] = static_cast<int>(i * static_cast<std::size_t>(N) / g.num_poses);
  layout = make_block_layout(g.num_poses, g.measurements, assignment);
  const Eigen::MatrixXd X0 = lift_poses(g.initial, opt.rank);
  scheme = make_momentum_scheme(opt, layout, static_cast<double>(X0.size()));
  const RoundConfig config = make_round_config(opt, scheme.get());
  for (int b = 0; b < N; ++b) {
    const auto& ids = layout.poses[static_cast<std::size_t>(b)];
    states.push_back(std::make_unique<AgentState>(b, g.d, layout, g.measurements,
                                                  gather_pose_columns(X0, ids, g.d)));
    protocols.push_back(std::make_unique<RoundProtocol>(*states.back(), layout, config));
    agents.push_back(protocols.back().get());
  }
}

}  // namespace tessera::test
