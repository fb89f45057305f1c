// The outer schedule of distributed GNC-TLS (in one process): capped solves before the final
// one, the known inliers' start, re-admission of measurements misjudged on a rough iterate.
#include <gtest/gtest.h>

#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_distributed.hpp>
#include <vector>

#include "gnc_fixtures.hpp"

namespace tessera {
namespace {

using test::grid_with_outliers;
using test::irbcd_gnc;
using test::robots_as_blocks;

GncDistributedResult run(const GeneratorResult& r, int cap, double mu_step, bool known_start) {
  GncDistributedOptions o = irbcd_gnc();
  o.robust.inner_max_rounds = cap;
  o.robust.mu_step = mu_step;
  o.known_inlier_start = known_start;
  return solve_gnc_distributed(r.graph, robots_as_blocks(r), o);
}

TEST(GncSchedule, CappedSolvesRejectTheSameSetAsFullSolvesInAFractionOfTheRounds) {
  const GeneratorResult r = grid_with_outliers(0.25);
  ASSERT_FALSE(r.outliers.empty());
  const GncDistributedResult full = run(r, 0, 1.4, true);
  const GncDistributedResult capped = run(r, RobustOptions{}.inner_max_rounds, 1.4, true);
  EXPECT_EQ(full.rejected, r.outliers);
  EXPECT_EQ(capped.rejected, r.outliers);
  EXPECT_NEAR(capped.final_solve.cost, full.final_solve.cost, 1e-6 * full.final_solve.cost);
  EXPECT_LT(2 * capped.total_rounds, full.total_rounds);
}

TEST(GncSchedule, TrueClosuresMisjudgedOnARoughIterateAreReadmitted) {
  // One round between weight updates and a steep mu schedule: the iterate lags, some true
  // closures still look wrong when their weights reach 0, and the check at the inlier set's
  // solution takes them back.
  const GeneratorResult r = grid_with_outliers(0.25);
  const GncDistributedResult g = run(r, 1, 4.0, true);
  EXPECT_GT(g.readmitted, 0u);
  EXPECT_EQ(g.rejected, r.outliers);
  for (std::size_t e : r.outliers) EXPECT_EQ(g.weights[e], 0.0);
}

TEST(GncSchedule, CappedReCheckPassesEndWithTheSameSetInFewerRounds) {
  // The schedule above leaves true closures to take back, so passes run: solved to the
  // tolerance each, or capped while the set may still change (the last one never is).
  const GeneratorResult r = grid_with_outliers(0.25);
  GncDistributedOptions o = irbcd_gnc();
  o.robust.inner_max_rounds = 1;
  o.robust.mu_step = 4.0;
  o.robust.recheck_max_rounds = 0;
  const GncDistributedResult full = solve_gnc_distributed(r.graph, robots_as_blocks(r), o);
  o.robust.recheck_max_rounds = 2;
  const GncDistributedResult capped = solve_gnc_distributed(r.graph, robots_as_blocks(r), o);
  ASSERT_GT(full.readmitted, 0u);
  EXPECT_EQ(full.rejected, r.outliers);
  EXPECT_EQ(capped.rejected, r.outliers);
  EXPECT_NEAR(capped.final_solve.cost, full.final_solve.cost, 1e-6 * full.final_solve.cost);
  EXPECT_LT(capped.total_rounds, full.total_rounds);
}

TEST(GncSchedule, APassFromASolvedPassThatChangesNothingEndsThePassesWithTheSameSet) {
  // A pass solved to the tolerance whose verdict still flips some measurements: the capped
  // pass after it settles them, and when it changes nothing its verdict stands
  // (RobustOptions::recheck_confirm_solved) instead of one more pass to the tolerance; the final
  // solve reaches the tolerance either way.
  // A steep mu schedule leaves true closures to take back after the first pass to the tolerance.
  const GeneratorResult r = grid_with_outliers(0.5);
  GncDistributedOptions o = irbcd_gnc();
  o.solver.certify = true;
  o.robust.inner_max_rounds = 5;
  o.robust.mu_step = 4.0;
  o.robust.recheck_max_rounds = 1;
  // This rule alone: with the fresh-start vote at a stalled pass (stall_kept_set_start) both
  // runs take 85 rounds, so the rule's saving does not show.
  o.stall_kept_set_start = false;
  o.robust.recheck_confirm_solved = false;
  const GncDistributedResult confirmed_by_full =
      solve_gnc_distributed(r.graph, robots_as_blocks(r), o);
  o.robust.recheck_confirm_solved = true;
  const GncDistributedResult confirmed = solve_gnc_distributed(r.graph, robots_as_blocks(r), o);
  EXPECT_EQ(confirmed_by_full.rejected, r.outliers);
  EXPECT_EQ(confirmed.rejected, r.outliers);
  EXPECT_GT(confirmed.readmitted, 0u);
  EXPECT_TRUE(confirmed.final_solve.certified);
  EXPECT_NEAR(confirmed.final_solve.cost, confirmed_by_full.final_solve.cost,
              1e-8 * confirmed_by_full.final_solve.cost);
  EXPECT_LT(confirmed.total_rounds, confirmed_by_full.total_rounds);
}

TEST(GncSchedule, ACleanGraphStartsWhereThePlainSolveStarts) {
  // On clean data the solver's own (chordal) start has the lower TLS cost: nothing to
  // reject, no outer step, and the rounds of the plain solve plus the capped first solve.
  const GeneratorResult clean = grid_with_outliers(0.0);
  const GncDistributedResult g = run(clean, RobustOptions{}.inner_max_rounds, 1.4, true);
  DistributedOptions plain_options = irbcd_gnc().solver;
  plain_options.refine.auto_interface_grad_tol = 0;  // its rounds to the tolerance, as GNC's
  const DistributedResult plain =
      solve_distributed(clean.graph, robots_as_blocks(clean), plain_options);
  EXPECT_TRUE(g.rejected.empty());
  EXPECT_EQ(g.outer_iterations, 0);
  EXPECT_LE(g.total_rounds, plain.rounds + RobustOptions{}.inner_max_rounds);
}

TEST(GncSchedule, TheKnownInliersStartNeedsFewerRoundsThanTheChordalStart) {
  // The chordal guess fits the wrong closures too; the odometry chains do not see them.
  const GeneratorResult r = grid_with_outliers(0.25);
  const GncDistributedResult known = run(r, 1, 1.4, true);
  const GncDistributedResult chordal = run(r, 1, 1.4, false);
  EXPECT_EQ(known.rejected, r.outliers);
  EXPECT_LT(known.total_rounds, chordal.total_rounds);
}

TEST(GncSchedule, WithoutConnectedKnownInliersTheSolversOwnStartIsUsed) {
  const GeneratorResult clean = grid_with_outliers(0.0);
  GncDistributedOptions o = irbcd_gnc();
  o.robust.known_inliers = KnownInliers::kNone;  // nothing known: no chain to start from
  const GncDistributedResult r = solve_gnc_distributed(clean.graph, robots_as_blocks(clean), o);
  EXPECT_TRUE(r.rejected.empty());
  EXPECT_EQ(r.readmitted, 0u);
}

}  // namespace
}  // namespace tessera
