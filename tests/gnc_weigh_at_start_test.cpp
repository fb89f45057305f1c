// RobustOptions::weigh_at_start: after the start vote, GNC's first weights and mu's start are
// taken at the voted start itself, with no plain solve's rounds before them.
#include <gtest/gtest.h>

#include <cmath>
#include <tessera/robust/gnc_distributed.hpp>

#include "gnc_fixtures.hpp"

namespace tessera {
namespace {

// The solver's defaults (--refine auto: GNC by Newton steps), certified.
GncDistributedOptions gnc_options(bool weigh_at_start) {
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  o.robust.weigh_at_start = weigh_at_start;
  return o;
}

GncDistributedResult solve(const GeneratorResult& dirty, const GncDistributedOptions& o) {
  return solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
}

GncDistributedResult solve(const GeneratorResult& dirty, bool weigh_at_start) {
  return solve(dirty, gnc_options(weigh_at_start));
}

// The 125-pose grid with 25 % random outliers, seed 1: after the plain solve's 5 rounds the
// first weighted Newton step's model does not hold there, so its weights are solved by rounds
// first (RobustOptions::newton_step_trust). Weighed at the voted start (the odometry chain, the
// minimiser of the known inliers' own problem) every weighted solve is a Newton step that holds:
// no round at all, the labels rejected, the same certified cost, fewer message steps.
TEST(GncWeighAtStart, GncWeighsAtTheVotedStartWithNoRoundAndEndsAtTheSameSetInFewerSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25, 1);
  const GncDistributedResult off = solve(dirty, false);
  const GncDistributedResult on = solve(dirty, true);
  ASSERT_GT(on.refine_message_steps, 0) << "the weighted solves should be Newton steps";
  EXPECT_EQ(off.rejected, dirty.outliers);
  EXPECT_GT(off.total_rounds, 5) << "a weighted solve should have run by rounds after the first";
  EXPECT_EQ(on.total_rounds, 0);
  EXPECT_EQ(on.rejected, dirty.outliers);
  EXPECT_EQ(on.readmitted, 0u);
  EXPECT_TRUE(on.final_solve.certified.value_or(false));
  EXPECT_NEAR(on.final_solve.cost, off.final_solve.cost, 1e-8 * std::abs(off.final_solve.cost));
  EXPECT_LT(message_steps(on), message_steps(off));
}

// Where GNC's weighted solves are rounds (RobustOptions::refine_passes off here; at 5 agents the
// 1000-pose grid, sphere2500, torus3D, manhattan3500) the first solve runs as before: weighed at
// the start, manhattan3500 with 25 % random outliers kept a wrong closure.
TEST(GncWeighAtStart, WhereGncsSolvesAreRoundsThePlainFirstSolveStays) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25, 1);
  GncDistributedOptions o = gnc_options(true);
  o.robust.refine_passes = false;
  const GncDistributedResult on = solve(dirty, o);
  o.robust.weigh_at_start = false;
  const GncDistributedResult off = solve(dirty, o);
  EXPECT_EQ(on.refine_message_steps, 0);
  EXPECT_EQ(on.total_rounds, off.total_rounds);
  EXPECT_EQ(on.exchange_steps, off.exchange_steps);
  EXPECT_EQ(on.rejected, off.rejected);
  EXPECT_EQ(on.final_solve.cost, off.final_solve.cost);
}

// The soft 300-pose city with 10 % group outliers, seed 2: nothing lies near the bound at the
// first weights, so GNC ends there (RobustOptions::jump_band) before any solve has run, and the
// kept set's fresh start, which wins its vote, becomes the passes' start.
TEST(GncWeighAtStart, AnEndAtTheFirstWeightsHandsTheKeptSetsStartToThePasses) {
  const GeneratorResult dirty = test::flexible_city(0.1, OutlierKind::kGroup, 2);
  const GncDistributedResult r = solve(dirty, true);
  EXPECT_EQ(r.outer_iterations, 1);
  EXPECT_EQ(r.rejected, dirty.outliers);
  EXPECT_TRUE(r.final_solve.certified.value_or(false));
}

}  // namespace
}  // namespace tessera
