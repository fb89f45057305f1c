// A run's message steps (docs/robust.md, "JSON and files": message_steps_total) against the
// longest chain of messages the in-process driver saw (DeliveryStats::longest_chain): every
// counted wait lies on one chain of messages, each sent after the previous one came in, so
// the count is what the run waits through one after another. Without certification: the
// certificate's own message steps are not in the count.
#include <gtest/gtest.h>

#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/robust/gnc_distributed.hpp>

#include "gnc_fixtures.hpp"

namespace tessera {
namespace {

TEST(MessageSteps, ACleanSolveCountsEveryWaitOfItsLongestChain) {
  const GeneratorResult clean = test::grid_with_outliers(0.0);
  DistributedOptions o;  // IRBCD, --refine auto: rounds, then the Newton refinement
  o.certify = false;
  const DistributedResult r = solve_distributed(clean.graph, test::robots_as_blocks(clean), o);
  ASSERT_EQ(r.solve_stages, 1);
  ASSERT_FALSE(r.refines.empty()) << "the rounds should hand over to the refinement";
  EXPECT_EQ(message_steps(r), static_cast<long long>(r.longest_chain));
}

TEST(MessageSteps, ARobustRunCountsEveryWaitOfItsLongestChain) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  for (bool ride_along : {true, false}) {
    GncDistributedOptions o;  // Newton steps in GNC
    o.robust.kind = RobustKind::kGncTls;
    o.robust.exchanges_ride_along = ride_along;
    o.robust.kept_solves_start_at_refinement = ride_along;
    const GncDistributedResult r =
        solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
    ASSERT_GT(r.outer_iterations, 2);
    if (ride_along)  // the weighted and kept set's solves start at their refinement
      ASSERT_LT(r.solve_stages, r.outer_iterations) << "a solve stage per weighted solve";
    else
      // (a weighted solve per weight update but the early end's, a pass and the final solve;
      // no first solve: RobustOptions::weigh_at_start)
      ASSERT_GE(r.solve_stages, r.outer_iterations) << "a solve stage per solve";
    EXPECT_EQ(message_steps(r), static_cast<long long>(r.longest_chain))
        << "exchanges_ride_along " << ride_along;
  }
}

}  // namespace
}  // namespace tessera
