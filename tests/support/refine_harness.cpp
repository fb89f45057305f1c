#include "refine_harness.hpp"

#include <gtest/gtest.h>

#include <tessera/generate/generator.hpp>
#include <tessera/solvers/centralized_solver.hpp>

namespace tessera::test {

PoseGraph refine_chain(std::size_t poses, std::uint64_t seed) {
  GeneratorOptions g;
  g.kind = TrajectoryKind::kGrid3d;
  g.num_poses = poses;
  g.max_loop_closures = 4;
  g.rotation_noise = 0.1;
  g.translation_noise = 1.0;
  g.seed = seed;
  return generate_pose_graph(g).graph;
}

double tight_optimum(const PoseGraph& g) {
  CentralizedOptions o;
  o.stop = CentralizedStop::kGradient;
  return solve_centralized(g, o).cost;
}

DistributedResult expect_same_refinement_in_any_delivery_order(const PoseGraph& g,
                                                               const std::vector<int>& parts,
                                                               const DistributedOptions& options,
                                                               std::uint64_t shuffle_seed) {
  DistributedOptions shuffled = options;
  shuffled.delivery = DeliveryOrder::kShuffled;
  shuffled.delivery_seed = shuffle_seed;
  DistributedResult a = solve_distributed(g, parts, options);
  const DistributedResult b = solve_distributed(g, parts, shuffled);
  EXPECT_EQ(a.refines.size(), 1u);
  EXPECT_EQ(b.refines.size(), 1u);
  if (a.refines.size() == 1 && b.refines.size() == 1) {
    EXPECT_EQ(a.refines[0].cg_iterations, b.refines[0].cg_iterations);
    EXPECT_EQ(a.refines[0].cost, b.refines[0].cost);  // bit for bit: sums in agent-id order
  }
  EXPECT_EQ(a.X, b.X);
  return a;
}

}  // namespace tessera::test
