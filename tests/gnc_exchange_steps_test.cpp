// GncDistributedResult::exchange_steps: GNC's own exchanges (poses, votes, weights, rejected
// sets, verdicts, gathers) are waits for peers like rounds, counted beside them.
#include <gtest/gtest.h>

#include <tessera/robust/gnc_distributed.hpp>

#include "gnc_fixtures.hpp"

namespace tessera {
namespace {

GncDistributedOptions capped(int outer) {
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  o.robust.max_outer_iterations = outer;
  o.robust.newton_mu_step_max = 0;  // mu's fixed step: the cap, not the schedule, ends GNC
  return o;
}

TEST(GncExchangeSteps, EachOuterStepTakesAPoseAndAWeightExchange) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  for (int k : {3, 6}) {
    const GncDistributedResult r =
        solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), capped(k));
    ASSERT_EQ(r.outer_iterations, k) << "25 % outliers take more than " << k << " outer steps";
    // Before each weight update the iterate's poses; mu's start vote once; the rejected set once.
    EXPECT_GE(r.exchange_steps, 2 * k + 2) << k << " outer steps";
  }
}

}  // namespace
}  // namespace tessera
