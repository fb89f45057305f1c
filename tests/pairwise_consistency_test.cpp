// Pairwise consistency maximisation before GNC (`--robust pcm-gnc`) on small generated graphs.
#include <gtest/gtest.h>

#include <string>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/robust/pairwise_consistency.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/util/input_error.hpp>

#include "gnc_fixtures.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

GeneratorResult city_with_groups(double fraction) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kCity;
  o.num_poses = 300;
  o.num_robots = 3;
  o.seed = 1;
  o.outlier_fraction = fraction;
  o.outlier_kind = OutlierKind::kGroup;
  return generate_pose_graph(o);
}

std::vector<Pose> odometry_chain(const PoseGraph& g, const std::vector<bool>& known) {
  PoseGraph chain;
  chain.d = g.d;
  chain.num_poses = g.num_poses;
  for (std::size_t e = 0; e < known.size(); ++e)
    if (known[e]) chain.measurements.push_back(g.measurements[e]);
  return distributed_initialization(chain, 1);
}

TEST(PairwiseConsistency, KeepsEveryTrueClosureAndFlagsEveryMemberOfAWrongGroup) {
  const GeneratorResult r = city_with_groups(0.25);
  ASSERT_FALSE(r.outliers.empty());
  const std::vector<bool> known = test::odometry_flags(r.graph);
  const double c2 = tls_threshold_squared(RobustOptions{}, r.graph.d, r.graph.num_measurements());
  const PairwiseConsistencyResult p =
      pairwise_consistency(r.graph, known, odometry_chain(r.graph, known), c2);
  EXPECT_EQ(p.inconsistent, r.outliers);
  // Members of one group agree with each other: the test is not just a residual bound.
  EXPECT_GT(p.consistent_pairs, 0u);
}

TEST(PairwiseConsistency, CleanClosuresAreAllConsistent) {
  const GeneratorResult r = city_with_groups(0.0);
  const std::vector<bool> known = test::odometry_flags(r.graph);
  const double c2 = tls_threshold_squared(RobustOptions{}, r.graph.d, r.graph.num_measurements());
  const PairwiseConsistencyResult p =
      pairwise_consistency(r.graph, known, odometry_chain(r.graph, known), c2);
  EXPECT_FALSE(p.candidates.empty());
  EXPECT_TRUE(p.inconsistent.empty());
}

TEST(PairwiseConsistency, PcmGncRejectsExactlyTheGroupsAndCertifiesTheRest) {
  const GeneratorResult dirty = city_with_groups(0.25);
  GncCentralizedOptions o;
  o.robust.kind = RobustKind::kPcmGnc;
  o.solver.initialization = Initialization::kOdometry;
  const GncCentralizedResult r = solve_gnc_centralized(dirty.graph, o);
  EXPECT_EQ(r.rejected, dirty.outliers);
  EXPECT_TRUE(r.final_solve.certified);
  const double fstar = solve_centralized(city_with_groups(0.0).graph).cost;
  EXPECT_NEAR(r.final_solve.cost, fstar, 1e-6 * fstar);
}

TEST(PairwiseConsistency, PcmGncWithoutConnectedKnownInliersSaysWhy) {
  const GeneratorResult dirty = city_with_groups(0.25);
  GncCentralizedOptions o;
  o.robust.kind = RobustKind::kPcmGnc;
  o.robust.known_inliers = KnownInliers::kNone;
  EXPECT_NE(test::input_error_of([&] {
              solve_gnc_centralized(dirty.graph, o);
            }).find("pcm-gnc: the known inliers do not connect"),
            std::string::npos);
}

TEST(PairwiseConsistency, ANegativeReadmissionCountNamesTheField) {
  RobustOptions o;
  o.readmission_passes = -1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.readmission_passes"));
}

}  // namespace
}  // namespace tessera
