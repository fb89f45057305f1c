// RobustOptions::gnc_refine_steps: with RobustOptions::refine_passes, where the team's interface
// fits the refinement's interface solves, GNC's weighted solves are Newton steps of the
// refinement instead of capped rounds, and the refined inlier passes hand over at once.
#include <gtest/gtest.h>

#include <tessera/robust/gnc_distributed.hpp>

#include "gnc_fixtures.hpp"
#include "robust/gnc_solve_setup.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

TEST(GncRefineSteps, ANegativeStepCountNamesTheField) {
  RobustOptions o;
  o.gnc_refine_steps = -1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.gnc_refine_steps"));
  o.gnc_refine_steps = 0;  // the weighted solves by rounds
  EXPECT_NO_THROW(o.validate());
}

TEST(GncRefineSteps, NewtonStepsInGncFindTheSameSetAtTheSameCertifiedCostInFewerMessageSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o;  // the solver's defaults: --refine auto
  o.robust.kind = RobustKind::kGncTls;
  o.robust.refine_passes = true;
  o.solver.certify = true;
  o.robust.gnc_refine_steps = 0;
  const GncDistributedResult rounds =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.gnc_refine_steps = 1;
  const GncDistributedResult newton =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  ASSERT_GT(rounds.refine_message_steps, 0) << "the interface should fit (the passes refine)";
  EXPECT_EQ(rounds.rejected, dirty.outliers);
  EXPECT_EQ(newton.rejected, dirty.outliers);
  EXPECT_NEAR(newton.final_solve.cost, rounds.final_solve.cost, 1e-9 * rounds.final_solve.cost);
  EXPECT_TRUE(newton.final_solve.certified.value_or(false));
  // The weighted solves and the passes take no rounds: only the first solve's are left.
  EXPECT_LE(newton.total_rounds, o.robust.inner_max_rounds + newton.final_solve.rounds);
  EXPECT_LT(message_steps(newton), message_steps(rounds));
}

// RobustOptions::step_sigma_every_agent: where the solver would have agent 0 alone factor Sigma
// and ship every solve (kShipSolves: here forced with a threshold of 0, the grid's interface is
// small), GNC's weighted Newton steps have every agent factor it instead: no wait for agent 0's
// solve, the same iterates.
TEST(GncRefineSteps, WeightedStepsThatFactorSigmaOnEveryAgentTakeTheSameIteratesInFewerSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  o.solver.refine.sigma_factoring = NewtonRefineOptions::SigmaFactoring::kShipSolves;
  o.solver.refine.ship_solves_min_coordinates = 0;
  o.robust.step_sigma_every_agent = false;
  const GncDistributedResult shipped =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.step_sigma_every_agent = true;
  const GncDistributedResult every =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  ASSERT_GT(shipped.refine_message_steps, 0) << "the weighted solves should be Newton steps";
  EXPECT_EQ(every.rejected, dirty.outliers);
  EXPECT_EQ(every.rejected, shipped.rejected);
  EXPECT_EQ(every.outer_iterations, shipped.outer_iterations);
  EXPECT_EQ(every.weights, shipped.weights);
  EXPECT_EQ(every.final_solve.cost, shipped.final_solve.cost);
  EXPECT_TRUE(every.final_solve.certified.value_or(false));
  EXPECT_EQ(every.exchange_steps, shipped.exchange_steps);
  EXPECT_EQ(every.total_rounds, shipped.total_rounds);
  // At least one message step less per weighted solve (one CG direction each).
  EXPECT_LE(every.refine_message_steps,
            shipped.refine_message_steps - (shipped.outer_iterations - 1));
}

// A weighted solve is one Newton step, one trial: its exact trial translations never wait for
// agent 0's solve. NewtonRefineOptions::translation_one_factor_min_poses applies to the inlier
// passes and the final solve, whose refinements take several trials, not to GNC's steps; the
// answer is the same either way.
TEST(GncRefineSteps, WeightedStepsSolveTheirTrialTranslationsOnEveryAgent) {
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.refine.translation_one_factor_min_poses = 0;  // agent 0's solves wherever allowed
  EXPECT_GT(
      gnc_solve_options(o, GncSolveKind::kGnc, false, true).refine.translation_one_factor_min_poses,
      1000000);
  EXPECT_EQ(gnc_solve_options(o, GncSolveKind::kInlierPass, false)
                .refine.translation_one_factor_min_poses,
            0);
  EXPECT_EQ(
      gnc_solve_options(o, GncSolveKind::kFinal, false).refine.translation_one_factor_min_poses, 0);

  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  o.solver.certify = true;
  const GncDistributedResult low =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.solver.refine.translation_one_factor_min_poses = 1000000;  // every agent factors
  const GncDistributedResult high =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  ASSERT_GT(high.refine_message_steps, 0) << "the weighted solves should be Newton steps";
  EXPECT_EQ(low.rejected, dirty.outliers);
  EXPECT_EQ(low.rejected, high.rejected);
  EXPECT_EQ(low.weights, high.weights);
  EXPECT_TRUE(low.final_solve.certified.value_or(false));
}

TEST(GncRefineSteps, WithoutRefinedPassesTheWeightedSolvesStayRounds) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.robust.refine_passes = false;
  o.solver.certify = true;
  o.robust.gnc_refine_steps = 0;
  const GncDistributedResult zero =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.gnc_refine_steps = 1;  // refine_passes is off: no effect
  const GncDistributedResult one =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  EXPECT_EQ(one.refine_message_steps, 0);
  EXPECT_EQ(one.total_rounds, zero.total_rounds);
  EXPECT_EQ(one.outer_iterations, zero.outer_iterations);
  EXPECT_EQ(one.rejected, zero.rejected);
  EXPECT_EQ(one.final_solve.cost, zero.final_solve.cost);
}

// RobustOptions::newton_mu_step_max: where GNC's weighted solves are Newton steps (refine_passes,
// gnc_refine_steps 1: the interface fits on the 125-pose grid), mu's step grows while no weight
// crosses 1/2: fewer outer steps, the same set and certified cost; where they are rounds the
// option changes nothing.
TEST(GncRefineSteps, BiggerMuStepsOnNewtonStepsKeepTheSetAndCostAndChangeNothingOnRounds) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o;  // the solver's defaults: --refine auto
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  ASSERT_EQ(o.robust.newton_mu_step_max, 4.0);
  const GncDistributedResult bigger =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.newton_mu_step_max = 0;
  const GncDistributedResult fixed =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  ASSERT_GT(fixed.refine_message_steps, 0) << "GNC's solves should be Newton steps here";
  EXPECT_EQ(bigger.rejected, dirty.outliers);
  EXPECT_EQ(fixed.rejected, dirty.outliers);
  EXPECT_LT(bigger.outer_iterations, fixed.outer_iterations);
  EXPECT_NEAR(bigger.final_solve.cost, fixed.final_solve.cost, 1e-9 * fixed.final_solve.cost);
  EXPECT_TRUE(bigger.final_solve.certified.value_or(false));

  o.robust.gnc_refine_steps = 0;  // GNC's weighted solves by rounds
  const GncDistributedResult rounds_off =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.newton_mu_step_max = 4;
  const GncDistributedResult rounds_on =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  EXPECT_EQ(rounds_on.outer_iterations, rounds_off.outer_iterations);
  EXPECT_EQ(rounds_on.total_rounds, rounds_off.total_rounds);
  EXPECT_EQ(rounds_on.rejected, rounds_off.rejected);
  EXPECT_EQ(rounds_on.final_solve.cost, rounds_off.final_solve.cost);
}

// RobustOptions::kept_solves_start_at_refinement: a refined inlier pass starts at the kept set's
// fresh start (whose neighbour poses came with it) or after the previous pass's pose exchange,
// and the final solve where the last pass ended, after that pass's pose exchange, at a gradient
// far below the rounds' tolerance. Their rounds would only repeat a pose exchange and stop at
// their first status, so they start at the Newton refinement: two message steps fewer each,
// the same points, set, cost and certificate.
TEST(GncRefineSteps, TheKeptSetsSolvesStartAtTheirRefinementWithTheSameAnswerAndCertificate) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  GncDistributedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  o.robust.kept_solves_start_at_refinement = false;
  const GncDistributedResult opened =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  o.robust.kept_solves_start_at_refinement = true;
  const GncDistributedResult started =
      solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  ASSERT_EQ(opened.final_solve_stages, 1);
  ASSERT_EQ(opened.final_solve.rounds, 0) << "the last pass should leave the rounds nothing";
  EXPECT_EQ(started.final_solve_stages, 0);
  EXPECT_EQ(started.final_solve.rounds, 0);
  EXPECT_LT(started.solve_stages, opened.solve_stages) << "a pass should start at its refinement";
  EXPECT_EQ(started.total_rounds, opened.total_rounds);
  EXPECT_EQ(started.refine_message_steps, opened.refine_message_steps);
  EXPECT_EQ(started.exchange_steps, opened.exchange_steps);
  EXPECT_EQ(started.outer_iterations, opened.outer_iterations);
  EXPECT_EQ(started.readmitted, opened.readmitted);
  EXPECT_EQ(started.rejected, dirty.outliers);
  EXPECT_EQ(started.rejected, opened.rejected);
  EXPECT_EQ(started.final_refine_message_steps, opened.final_refine_message_steps);
  EXPECT_EQ(started.final_solve.X, opened.final_solve.X);
  EXPECT_EQ(started.final_solve.cost, opened.final_solve.cost);
  EXPECT_EQ(started.final_solve.relaxation_cost, opened.final_solve.relaxation_cost);
  ASSERT_TRUE(opened.final_solve.certified.value_or(false));
  EXPECT_TRUE(started.final_solve.certified.value_or(false));
  EXPECT_EQ(started.final_solve.min_eigenvalue, opened.final_solve.min_eigenvalue);
  EXPECT_EQ(started.final_solve.longest_chain + 2, opened.final_solve.longest_chain);
}

TEST(GncRefineSteps, ANewtonMuStepMaxOfOneNamesTheField) {
  RobustOptions o;
  o.newton_mu_step_max = 1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.newton_mu_step_max"));
  o.newton_mu_step_max = 0;  // none
  EXPECT_NO_THROW(o.validate());
}

}  // namespace
}  // namespace tessera
