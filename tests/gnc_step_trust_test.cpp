// RobustOptions::newton_step_trust: where GNC's weighted solves are Newton steps, the weights are
// updated at a step's point only when its quadratic model held there; otherwise the same weighted
// problem is solved by rounds from the step's start first.
#include <gtest/gtest.h>

#include <tessera/robust/gnc_distributed.hpp>

#include "gnc_fixtures.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

TEST(GncStepTrust, ATrustOutsideZeroToOneNamesTheField) {
  RobustOptions o;
  o.newton_step_trust = 1.5;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.newton_step_trust"));
  o.newton_step_trust = -0.1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.newton_step_trust"));
  o.newton_step_trust = 0;  // off
  EXPECT_NO_THROW(o.validate());
}

// The 125-pose grid with 25 % random outliers, seed 1: the first solve's 5 rounds leave it rough,
// and the first weighted Newton step from there is one the model does not predict. Weighed at
// that step's end, GNC's own rejected set holds true closures that only the inlier passes take
// back; with the test, the step's weights are solved by rounds first and GNC's own set is the
// labels (nothing for the passes to take back), in fewer message steps.
TEST(GncStepTrust, WeightsAtUntrustedNewtonStepsCutTrueClosuresThatRoundsFirstKeep) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25, 1);
  GncDistributedOptions o;  // the solver's defaults: --refine auto, GNC by Newton steps
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  // After the plain solve's rounds (weighed at the voted start instead, RobustOptions::
  // weigh_at_start, no Newton step here fails the test: tests/gnc_weigh_at_start_test.cpp).
  o.robust.weigh_at_start = false;
  o.robust.newton_step_trust = 0;
  const GncDistributedResult off =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.newton_step_trust = 0.75;
  const GncDistributedResult on =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  ASSERT_GT(off.refine_message_steps, 0) << "the weighted solves should be Newton steps";
  EXPECT_GT(off.readmitted, 0u) << "GNC's own set should hold true closures without the test";
  EXPECT_EQ(on.readmitted, 0u);
  EXPECT_EQ(on.rejected, dirty.outliers);
  EXPECT_TRUE(on.final_solve.certified.value_or(false));
  EXPECT_GT(on.total_rounds, off.total_rounds) << "a weighted solve should have run by rounds";
  EXPECT_LT(message_steps(on), message_steps(off));
}

}  // namespace
}  // namespace tessera
