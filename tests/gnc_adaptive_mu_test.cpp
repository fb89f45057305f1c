// RobustOptions::mu_step_max (the adaptive mu schedule of the distributed GNC): bigger steps of
// mu while no weight crosses 1/2, the same answer in fewer outer steps, and the option's range;
// RobustOptions::mu_step_hold: only weights that fall below 1/2 hold the bigger step back.
#include <gtest/gtest.h>

#include <tessera/robust/gnc_distributed.hpp>
#include <tessera/util/input_error.hpp>

#include "gnc_fixtures.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

TEST(GncAdaptiveMu, ABadMaximumStepNamesTheField) {
  RobustOptions o;
  o.mu_step_max = 1.2;  // below mu_step (1.4)
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.mu_step_max"));
  o.mu_step_max = 0;  // off
  EXPECT_NO_THROW(o.validate());
  o.mu_step_max = 1.4;  // the fixed step itself
  EXPECT_NO_THROW(o.validate());
}

TEST(GncAdaptiveMu, BiggerStepsWhileTheSetStaysEndWithTheSameSetInFewerOuterSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  o.robust.newton_mu_step_max = 0;  // the fixed step on Newton steps too
  const GncDistributedResult fixed =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.mu_step_max = 4;
  const GncDistributedResult adaptive =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  EXPECT_EQ(fixed.rejected, dirty.outliers);
  EXPECT_EQ(adaptive.rejected, dirty.outliers);
  EXPECT_LT(adaptive.outer_iterations, fixed.outer_iterations);
  EXPECT_NEAR(adaptive.final_solve.cost, fixed.final_solve.cost, 1e-9 * fixed.final_solve.cost);
  EXPECT_TRUE(adaptive.final_solve.certified.value_or(false));
}

TEST(GncAdaptiveMu, ABadHoldNamesTheField) {
  RobustOptions o;
  o.mu_step_hold = static_cast<MuStepHold>(7);
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.mu_step_hold"));
  EXPECT_EQ(parse_mu_step_hold(mu_step_hold_name(MuStepHold::kCrossings)), MuStepHold::kCrossings);
  EXPECT_EQ(parse_mu_step_hold(mu_step_hold_name(MuStepHold::kFalls)), MuStepHold::kFalls);
  EXPECT_THROW(parse_mu_step_hold("rises"), InputError);
}

// Where GNC's weighted solves are Newton steps (the 125-pose grid, seed 1: the interface fits), the
// bigger step of mu (newton_mu_step_max) applies after every update at which no weight fell below
// 1/2, while weights rising past 1/2 (what a larger mu does at a fixed iterate) no longer hold it
// back: fewer outer steps, the same rejected set and certified cost.
TEST(GncAdaptiveMu, OnlyFallingWeightsHoldTheBiggerStepBackAndTheSetStaysInFewerOuterSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25, 1);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  // Every weighted solve a Newton step as it ends: with newton_step_trust the rough first steps
  // here are solved by rounds first, and both holds then take 6 outer steps.
  o.robust.newton_step_trust = 0;
  // From the plain solve's rough point, where the weights fall and rise over several updates
  // (weighed at the voted start instead, both holds take 6 outer steps here).
  o.robust.weigh_at_start = false;
  ASSERT_EQ(o.robust.mu_step_hold, MuStepHold::kFalls);
  const GncDistributedResult falls =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.mu_step_hold = MuStepHold::kCrossings;
  const GncDistributedResult crossings =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  ASSERT_GT(crossings.refine_message_steps, 0) << "GNC's solves should be Newton steps here";
  EXPECT_EQ(falls.rejected, dirty.outliers);
  EXPECT_EQ(crossings.rejected, dirty.outliers);
  EXPECT_LT(falls.outer_iterations, crossings.outer_iterations);
  EXPECT_NEAR(falls.final_solve.cost, crossings.final_solve.cost,
              1e-9 * crossings.final_solve.cost);
  EXPECT_TRUE(falls.final_solve.certified.value_or(false));
}

}  // namespace
}  // namespace tessera
