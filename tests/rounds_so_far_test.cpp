// CertifiedAgent::rounds_so_far counts the solve stage that is running, not only the ended
// ones (total_rounds): an agent's per-round memory lines (runtime/round_loop.cpp) follow it.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <memory>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/certified_agent.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/problem/lifting.hpp>
#include <vector>

namespace tessera {
namespace {

// Forwards to a certified agent and records its rounds_so_far after every message it handled.
class Recording : public AgentProcess {
 public:
  explicit Recording(CertifiedAgent& inner) : inner_(inner) {}
  std::vector<OutgoingMessage> start() override { return inner_.start(); }
  std::vector<OutgoingMessage> handle(const ProtocolMessage& m) override {
    auto out = inner_.handle(m);
    seen.push_back(inner_.rounds_so_far());
    return out;
  }
  bool done() const override { return inner_.done(); }
  std::size_t messages_needed() const override { return inner_.messages_needed(); }
  std::optional<AwaitedMessages> awaited() const override { return inner_.awaited(); }

  std::vector<int> seen;

 private:
  CertifiedAgent& inner_;
};

TEST(RoundsSoFar, CountTheRunningSolveStageAndEndAtTheTotal) {
  GeneratorOptions g;
  g.kind = TrajectoryKind::kGrid3d;
  g.num_poses = 200;
  g.num_robots = 4;
  g.seed = 1;
  g.rotation_noise = 0.05;
  g.translation_noise = 0.25;
  const GeneratorResult gen = generate_pose_graph(g);
  const PoseGraph& graph = gen.graph;
  std::vector<int> blocks(graph.num_poses);
  for (std::size_t i = 0; i < blocks.size(); ++i)
    blocks[i] = static_cast<int>(i * 4 / graph.num_poses);
  const BlockLayout layout = make_block_layout(graph.num_poses, graph.measurements, blocks);

  DistributedOptions o;
  o.rank = 3;
  o.grad_norm_tol = 1e-6;
  o.max_rounds = 40;
  o.certify = false;
  o.refine.enabled = false;
  const Eigen::MatrixXd X0 = lift_poses(gen.ground_truth, o.rank);
  std::vector<std::unique_ptr<AgentState>> states;
  std::vector<std::unique_ptr<CertifiedAgent>> agents;
  std::vector<std::unique_ptr<Recording>> recorders;
  std::vector<AgentProcess*> processes;
  for (int b = 0; b < layout.num_blocks; ++b) {
    states.push_back(std::make_unique<AgentState>(
        b, graph.d, layout, graph.measurements,
        gather_pose_columns(X0, layout.poses[static_cast<std::size_t>(b)], graph.d),
        o.algorithm_block_update()));
    agents.push_back(std::make_unique<CertifiedAgent>(*states.back(), layout, o));
    recorders.push_back(std::make_unique<Recording>(*agents.back()));
    processes.push_back(recorders.back().get());
  }
  run_in_process(processes, DeliveryOrder::kFifo);

  for (std::size_t b = 0; b < agents.size(); ++b) {
    const int total = agents[b]->total_rounds();
    ASSERT_GT(total, 2);  // the noisy truth is not the optimum: several rounds
    const std::vector<int>& seen = recorders[b]->seen;
    ASSERT_FALSE(seen.empty());
    EXPECT_EQ(seen.back(), total);
    // An adaptive restart takes the count back one round, so it need not only grow.
    const int restarts = agents[b]->total_restarts();
    bool midway = false;
    for (int r : seen) {
      EXPECT_LE(r, total + restarts);
      midway = midway || (r > 0 && r < total);
    }
    EXPECT_TRUE(midway) << "agent " << b << " saw no round count while it solved";
  }
}

}  // namespace
}  // namespace tessera
