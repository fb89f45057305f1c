// GNC-TLS around the distributed solvers (in one process) on small generated graphs.
#include <gtest/gtest.h>

#include <algorithm>
#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <vector>

namespace tessera {
namespace {

GeneratorResult grid_with_outliers(double fraction) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 125;
  o.num_robots = 5;
  o.seed = 3;
  o.outlier_fraction = fraction;
  return generate_pose_graph(o);
}

// The generator's robots as the blocks: robot r owns a contiguous id range.
std::vector<int> robots_as_blocks(const GeneratorResult& r) {
  return std::vector<int>(r.robot_of.begin(), r.robot_of.end());
}

GncDistributedOptions irbcd_gnc() {
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.algorithm = DistributedAlgorithm::kIrbcd;
  o.solver.grad_norm_tol = 1e-3;
  return o;
}

TEST(GncDistributed, EveryWeightIsComputedByExactlyTheOwnerOfTheLowerPose) {
  const GeneratorResult r = grid_with_outliers(0.25);
  const std::vector<int> blocks = robots_as_blocks(r);
  const Eigen::MatrixXd X = Eigen::MatrixXd::Zero(5, 4 * 125);
  std::vector<int> computed_by(r.graph.num_measurements(), -1);
  std::size_t cut = 0;
  for (int a = 0; a < 5; ++a) {
    const AgentWeights mine = agent_weights(a, r.graph, blocks, X, irbcd_gnc().robust, 10, 1);
    for (std::size_t e : mine.measurements) {
      EXPECT_EQ(computed_by[e], -1) << "measurement " << e << " weighted twice";
      computed_by[e] = a;
    }
  }
  for (std::size_t e = 0; e < r.graph.num_measurements(); ++e) {
    const Measurement& m = r.graph.measurements[e];
    EXPECT_EQ(computed_by[e], blocks[std::min(m.i, m.j)]);
    if (blocks[m.i] != blocks[m.j]) ++cut;
  }
  EXPECT_GT(cut, 0u);  // the property matters: some measurements join two agents
}

TEST(GncDistributed, RejectsTheSameOutliersAsTheCentralizedLoopAndCertifiesTheInlierSet) {
  const GeneratorResult clean = grid_with_outliers(0.0);
  const GeneratorResult dirty = grid_with_outliers(0.25);
  GncDistributedOptions o = irbcd_gnc();
  o.solver.certify = true;
  const GncDistributedResult distributed =
      solve_gnc_distributed(dirty.graph, robots_as_blocks(dirty), o);
  EXPECT_EQ(distributed.rejected, dirty.outliers);
  GncCentralizedOptions c;
  c.robust.kind = RobustKind::kGncTls;
  const GncCentralizedResult centralized = solve_gnc_centralized(dirty.graph, c);
  EXPECT_EQ(distributed.rejected, centralized.rejected);

  const double fstar = solve_centralized(clean.graph).cost;
  EXPECT_NEAR(distributed.final_solve.cost, fstar, 1e-5 * fstar);
  EXPECT_TRUE(distributed.final_solve.certified.value_or(false));
  EXPECT_GE(distributed.total_rounds, distributed.final_solve.rounds);
  EXPECT_GT(distributed.total_bytes, distributed.final_solve.bytes_exchanged);
}

TEST(GncDistributed, CleanGraphLosesNothing) {
  const GeneratorResult clean = grid_with_outliers(0.0);
  const GncDistributedResult r =
      solve_gnc_distributed(clean.graph, robots_as_blocks(clean), irbcd_gnc());
  EXPECT_TRUE(r.rejected.empty());
  for (double w : r.weights) EXPECT_EQ(w, 1.0);
}

}  // namespace
}  // namespace tessera
