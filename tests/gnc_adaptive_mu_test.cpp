// RobustOptions::mu_step_max (the adaptive mu schedule of the distributed GNC): bigger steps of
// mu while no weight crosses 1/2, the same answer in fewer outer steps, and the option's range.
#include <gtest/gtest.h>

#include <tessera/robust/gnc_distributed.hpp>

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

}  // namespace
}  // namespace tessera
