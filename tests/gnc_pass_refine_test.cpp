// RobustOptions::refine_passes: under `--refine auto` the inlier passes solved to the tolerance
// hand over to the Newton refinement where the team's interface fits its interface solves.
#include <gtest/gtest.h>

#include <tessera/robust/gnc_distributed.hpp>

#include "gnc_fixtures.hpp"

namespace tessera {
namespace {

TEST(GncPassRefine, RefinedPassesEndWithTheSameSetAndCostAndCountTheirMessageSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o;  // the solver's defaults: --refine auto, gradient 0.01
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  o.robust.refine_passes = false;
  const GncDistributedResult rounds =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.refine_passes = true;
  const GncDistributedResult refined =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  EXPECT_EQ(rounds.refine_message_steps, 0);  // off: the passes are solved by rounds alone
  EXPECT_GT(refined.refine_message_steps, 0);
  EXPECT_EQ(refined.rejected, dirty.outliers);
  EXPECT_EQ(rounds.rejected, dirty.outliers);
  EXPECT_NEAR(refined.final_solve.cost, rounds.final_solve.cost, 1e-9 * rounds.final_solve.cost);
  EXPECT_TRUE(refined.final_solve.certified.value_or(false));
  EXPECT_LT(refined.total_rounds, rounds.total_rounds);
}

}  // namespace
}  // namespace tessera
