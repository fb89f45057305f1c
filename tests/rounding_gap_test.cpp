// A certificate of the relaxation certifies the rounded estimate only when the relaxation is
// tight: on a graph with heavy rotation noise the certified X rounds far above f(X), and the
// solvers then report the estimate as not certified.

#include <gtest/gtest.h>

#include <optional>
#include <tessera/certification/rounding_gap.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/solvers/centralized_solver.hpp>

namespace tessera {
namespace {

PoseGraph grid(double rotation_noise) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 64;
  o.num_robots = 2;
  o.rotation_noise = rotation_noise;
  o.translation_noise = 0.5;
  o.seed = 1;
  return generate_pose_graph(o).graph;
}

TEST(RoundingGap, IsRelativeToTheRelaxationCostAndBoundedBelowByOne) {
  EXPECT_DOUBLE_EQ(relative_rounding_gap(110.0, 100.0), 0.1);
  EXPECT_DOUBLE_EQ(relative_rounding_gap(0.5, 0.25), 0.25);  // |f(X)| < 1: absolute gap
  EXPECT_LT(relative_rounding_gap(99.0, 100.0), 0.0);
  EXPECT_TRUE(rounding_is_tight(100.0 + 1e-4, 100.0));
  EXPECT_FALSE(rounding_is_tight(100.01, 100.0));
  EXPECT_TRUE(rounding_is_tight(100.01, 100.0, 1e-3));
}

TEST(RoundingGap, OnlyACertifiedRelaxationWithALooseRoundingChangesTheVerdict) {
  EXPECT_EQ(estimate_certified(true, 100.0, 100.0), std::optional<bool>(true));
  EXPECT_EQ(estimate_certified(true, 101.0, 100.0), std::optional<bool>(false));
  EXPECT_EQ(estimate_certified(false, 100.0, 100.0), std::optional<bool>(false));
  EXPECT_EQ(estimate_certified(std::nullopt, 101.0, 100.0), std::nullopt);
}

TEST(RoundingGap, ACertifiedRelaxationThatIsNotTightLeavesTheEstimateUncertified) {
  const PoseGraph g = grid(0.5);
  const CentralizedResult r = solve_centralized(g);
  ASSERT_FALSE(r.levels.empty());
  // The relaxation's certificate holds, yet rounding lands well above f(X).
  EXPECT_TRUE(r.levels.back().certified);
  EXPECT_GT(relative_rounding_gap(r.cost, r.relaxation_cost), 1e-3);
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_FALSE(*r.certified);
  EXPECT_NE(r.full_report().find("not tight"), std::string::npos) << r.full_report();
}

TEST(RoundingGap, OnLowNoiseTheEstimateOfATightRelaxationIsCertified) {
  const PoseGraph g = grid(0.01);
  const CentralizedResult r = solve_centralized(g);
  EXPECT_TRUE(r.certified.value_or(false));
  EXPECT_LE(relative_rounding_gap(r.cost, r.relaxation_cost), 1e-9);
}

TEST(RoundingGap, TheDistributedSolverAppliesTheSameRule) {
  DistributedOptions opt;
  opt.certify = true;
  opt.grad_norm_tol = 1e-4;
  const PoseGraph noisy = grid(0.5);
  const DistributedResult r =
      solve_distributed(noisy, sequential_partition(noisy.num_poses, 4), opt);
  ASSERT_TRUE(r.certified.has_value());
  if (!r.certificates.empty() && r.certificates.back().result.certified) {
    EXPECT_GT(relative_rounding_gap(r.cost, r.relaxation_cost), kDefaultRoundingGapTolerance);
  }
  EXPECT_FALSE(*r.certified);
  const PoseGraph clean = grid(0.01);
  const DistributedResult c =
      solve_distributed(clean, sequential_partition(clean.num_poses, 4), opt);
  EXPECT_TRUE(c.certified.value_or(false));
}

}  // namespace
}  // namespace tessera
