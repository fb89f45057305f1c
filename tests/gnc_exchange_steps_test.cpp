// GncDistributedResult::exchange_steps: GNC's own exchanges (poses, votes, weights, rejected
// sets, verdicts, gathers) are waits for peers like rounds, counted beside them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <tessera/robust/gnc_distributed.hpp>
#include <tuple>
#include <vector>

#include "gnc_fixtures.hpp"

namespace tessera {
namespace {

// GNC-TLS, certified; the runs compared below differ in one RobustOptions switch.
GncDistributedOptions certified_tls() {
  GncDistributedOptions o;  // --refine auto, refined passes: Newton steps in GNC
  o.robust.kind = RobustKind::kGncTls;
  o.solver.certify = true;
  return o;
}

using Weights = std::tuple<int, int, std::vector<std::uint64_t>, std::vector<double>>;

// Solves `dirty` with its robots as the blocks, with every agent's weights after every outer
// step in `seen`, sorted (the agents report in the order their messages come in, which the
// steps change).
GncDistributedResult solve_recording_weights(const GeneratorResult& dirty, GncDistributedOptions o,
                                             std::vector<Weights>& seen) {
  o.weight_observer = [&](int agent, int outer, const std::vector<std::uint64_t>& index,
                          const std::vector<double>& w) {
    seen.emplace_back(agent, outer, index, w);
  };
  GncDistributedResult r = solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
  std::sort(seen.begin(), seen.end());
  return r;
}

// `dirty` solved with certified_tls() and the RobustOptions switch `flag` set to `on`.
GncDistributedResult solve_with(const GeneratorResult& dirty, bool RobustOptions::*flag, bool on) {
  GncDistributedOptions o = certified_tls();
  o.robust.*flag = on;
  return solve_gnc_distributed(dirty.graph, test::robots_as_blocks(dirty), o);
}

// The same run but for its message steps: the same set, outer steps, rounds, refinements' steps
// and final iterate, to the bit.
void expect_same_run(const GncDistributedResult& a, const GncDistributedResult& b) {
  EXPECT_EQ(a.rejected, b.rejected);
  EXPECT_EQ(a.readmitted, b.readmitted);
  EXPECT_EQ(a.outer_iterations, b.outer_iterations);
  EXPECT_EQ(a.total_rounds, b.total_rounds);
  EXPECT_EQ(a.refine_message_steps, b.refine_message_steps);
  EXPECT_EQ(a.final_solve.cost, b.final_solve.cost);
  EXPECT_EQ(a.final_solve.X, b.final_solve.X);
}

GncDistributedOptions capped(int outer) {
  GncDistributedOptions o = certified_tls();
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

// RobustOptions::exchanges_ride_along: where GNC's weighted solves are single Newton steps (the
// interface fits on the 125-pose grid), the poses of each weight update travel beside the
// trial's sums, the rejected set with the last weights, the values agent 0 needs for the kept
// set's fresh start with mu's start votes and the start's neighbour poses with agent 0's
// answer; the run is otherwise the same.
TEST(GncExchangeSteps, ExchangesThatRideAlongLeaveTheRunAsItWasInFewerSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  auto run = [&](bool ride_along, std::vector<Weights>& seen) {
    GncDistributedOptions o = certified_tls();
    o.robust.exchanges_ride_along = ride_along;
    o.robust.weights_ride_trial_sums = false;  // its own test below
    o.robust.kept_vote_rides_weights = false;  // likewise
    return solve_recording_weights(dirty, o, seen);
  };
  std::vector<Weights> seen_apart, seen_along;
  const GncDistributedResult apart = run(false, seen_apart);
  const GncDistributedResult along = run(true, seen_along);
  ASSERT_GT(apart.refine_message_steps, 0) << "GNC's weighted solves should be Newton steps";
  ASSERT_GT(apart.outer_iterations, 2);
  EXPECT_EQ(along.rejected, dirty.outliers);
  expect_same_run(along, apart);
  EXPECT_EQ(seen_along, seen_apart);  // every agent's weights after every outer step, to the bit
  EXPECT_TRUE(along.final_solve.certified.value_or(false));
  // The pose exchange before each weight update but the first (which follows the plain solve's
  // rounds) and the rejected set's exchange; at the kept set's fresh start (one, after GNC's
  // early end: the iterate's poses are the last weight update's) the values' way to agent 0 and
  // the pose exchange of both starts.
  EXPECT_EQ(apart.exchange_steps - along.exchange_steps, apart.outer_iterations + 2);
  // Each weighted solve (a Newton step, after a pose exchange of its start) starts at its
  // refinement: no solve stage of its own. Left: the plain solve, the passes, the final solve.
  // (An outer step ended early by a jump has no weighted solve after its weight update.)
  EXPECT_GE(apart.solve_stages - along.solve_stages, apart.outer_iterations - 1);
  EXPECT_EQ(along.final_solve_stages, apart.final_solve_stages);
  // Every step left out was a real wait: the longest chain of messages is shorter by as many.
  EXPECT_EQ(static_cast<std::int64_t>(apart.longest_chain - along.longest_chain),
            message_steps(apart) - message_steps(along));
}

// RobustOptions::weights_ride_trial_sums: each weight update after a weighted solve by a single
// Newton step is computed at the trial point and travels beside the trial's sums; the trial
// accepted, the weight exchange after the solve waits for nothing. The same weights, set and
// cost; one message step fewer per such update, each a real wait (the longest chain).
TEST(GncExchangeSteps, WeightsBesideTheTrialSumsLeaveTheRunAsItWasInFewerSteps) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  auto run = [&](bool beside, std::vector<Weights>& seen) {
    GncDistributedOptions o = certified_tls();
    o.robust.weights_ride_trial_sums = beside;
    return solve_recording_weights(dirty, o, seen);
  };
  std::vector<Weights> seen_apart, seen_beside;
  const GncDistributedResult apart = run(false, seen_apart);
  const GncDistributedResult beside = run(true, seen_beside);
  ASSERT_GT(apart.refine_message_steps, 0) << "GNC's weighted solves should be Newton steps";
  ASSERT_GT(apart.outer_iterations, 3);
  EXPECT_EQ(beside.rejected, dirty.outliers);
  expect_same_run(beside, apart);
  EXPECT_EQ(seen_beside, seen_apart);  // every agent's weights after every outer step, to the bit
  EXPECT_TRUE(beside.final_solve.certified.value_or(false));
  // Every update after a weighted solve (all but the first, after the plain solve's rounds)
  // whose trial was accepted: at least one, at most one per such update.
  const int saved = apart.exchange_steps - beside.exchange_steps;
  EXPECT_GE(saved, 1);
  EXPECT_LE(saved, apart.outer_iterations - 1);
  EXPECT_EQ(beside.solve_stages, apart.solve_stages);
  EXPECT_EQ(message_steps(apart) - message_steps(beside), saved);
  EXPECT_EQ(static_cast<std::int64_t>(apart.longest_chain - beside.longest_chain), saved);
}

// RobustOptions::first_solve_takes_start_poses: the start vote's exchange of both starts' poses
// is also the first solve's opening exchange; the run is the same, one message step shorter.
TEST(GncExchangeSteps, TheFirstSolveTakesTheStartVotesPosesAndTheRunIsOneStepShorter) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  const auto flag = &RobustOptions::first_solve_takes_start_poses;
  const GncDistributedResult apart = solve_with(dirty, flag, false);
  const GncDistributedResult taken = solve_with(dirty, flag, true);
  ASSERT_TRUE(apart.final_solve.certified.value_or(false));
  expect_same_run(taken, apart);
  EXPECT_EQ(apart.exchange_steps - taken.exchange_steps, 1);
  EXPECT_EQ(static_cast<std::int64_t>(apart.longest_chain - taken.longest_chain), 1);
}

// RobustOptions::pass_poses_ride_trial_sums: a refined inlier pass's trial poses go out beside
// each trial's sums; the pose exchange after the pass reads the last accepted trial's. The run is
// the same, one message step shorter per such pass.
TEST(GncExchangeSteps, APassReadsItsLastAcceptedTrialsPosesAndTheRunIsShorter) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  const auto flag = &RobustOptions::pass_poses_ride_trial_sums;
  const GncDistributedResult apart = solve_with(dirty, flag, false);
  const GncDistributedResult beside = solve_with(dirty, flag, true);
  ASSERT_TRUE(apart.final_solve.certified.value_or(false));
  expect_same_run(beside, apart);
  const int saved = apart.exchange_steps - beside.exchange_steps;
  EXPECT_GE(saved, 1);  // at least the pass after GNC
  EXPECT_EQ(static_cast<std::int64_t>(apart.longest_chain - beside.longest_chain), saved);
}

// RobustOptions::kept_vote_rides_weights: after GNC's early end the vote between the iterate and
// the kept set's fresh start takes the iterate's cost from the last weights messages and the
// start's from agent 0's answer, summed as the vote sums them; the run is the same (the same
// vote outcome, every later step alike), one message step shorter.
TEST(GncExchangeSteps, TheFreshStartsVoteRidesTheWeightsAndTheRunIsOneStepShorter) {
  const GeneratorResult dirty = test::grid_with_outliers(0.25);
  const auto flag = &RobustOptions::kept_vote_rides_weights;
  const GncDistributedResult voted = solve_with(dirty, flag, false);
  const GncDistributedResult ridden = solve_with(dirty, flag, true);
  ASSERT_TRUE(voted.final_solve.certified.value_or(false));
  ASSERT_FALSE(voted.rejected.empty());
  expect_same_run(ridden, voted);
  EXPECT_EQ(voted.exchange_steps - ridden.exchange_steps, 1);
  EXPECT_EQ(static_cast<std::int64_t>(voted.longest_chain - ridden.longest_chain), 1);
}

}  // namespace
}  // namespace tessera
