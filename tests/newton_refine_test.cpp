// The distributed Newton refinement (newton_refine.hpp): from where the block-coordinate rounds
// stop, it reaches the centralized optimum of a long chain (the case the rounds are slow on)
// in a few trust-region steps; every agent takes the same steps whatever the delivery order;
// its options refuse bad values by name.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/online/live_blocks.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "distributed/rounds_tail.hpp"
#include "refine_harness.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// The refinement tests' chain (refine_harness.hpp) at 600 poses. With 4 agents the rounds stop
// at gradient 0.01 1.5e-5 above f* (159 rounds).
PoseGraph long_chain() {
  return test::refine_chain(600, 3);
}

DistributedOptions refined(bool on) {
  DistributedOptions o;
  o.grad_norm_tol = 0.01;
  set_refine_mode(o.refine, on ? "newton" : "none");
  return o;
}

TEST(NewtonRefine, ReachesTheCentralizedOptimumWhereTheRoundsStopShortOfIt) {
  const PoseGraph g = long_chain();
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  const double fstar = test::tight_optimum(g);
  const DistributedResult plain = solve_distributed(g, parts, refined(false));
  const DistributedResult newton = solve_distributed(g, parts, refined(true));
  // The same rounds first (the refinement starts where the plain run stops).
  EXPECT_EQ(newton.rounds, plain.rounds);
  ASSERT_EQ(newton.refines.size(), 1u);
  const NewtonRefineResult& n = newton.refines.front();
  EXPECT_TRUE(n.stop_reason == "grad_norm" || n.stop_reason == "relative_decrease")
      << n.stop_reason;
  EXPECT_EQ(n.initial_cost, plain.relaxation_cost);
  EXPECT_GE(n.accepted_steps, 1);
  EXPECT_LE(n.steps, 6);
  // Each CG iteration is one neighbour exchange and one all-agent sum; each step adds the
  // exchange of its trial point, the exact solve of its translations (one sum) and its cost's
  // sum, plus the start's sum, a step's last CG exchange and the interface matrix's sum at
  // each new point but the start, whose shares ride in the start's sum, and those whose shares
  // rode in the accepted trial's sum.
  EXPECT_GT(n.translation_interface_poses, 0);
  EXPECT_EQ(n.translation_iterations, 0);
  EXPECT_EQ(n.translation_solves, n.steps);
  EXPECT_GE(n.exchanges, n.cg_iterations + n.steps);
  EXPECT_LE(n.exchanges, n.cg_iterations + 2 * n.steps);
  ASSERT_GT(n.interface_coordinates, 0);
  EXPECT_GE(n.interface_shares_carried, 1);
  EXPECT_EQ(n.reductions, n.exchanges + n.translation_solves + n.coarse_assemblies +
                              n.interface_factorizations + n.interface_fallbacks -
                              n.interface_shares_carried);
  EXPECT_LE(n.coarse_assemblies, n.accepted_steps + 1);
  // The rounds stop measurably above f*; the refined estimate is at f*.
  const double gap_plain = (plain.cost - fstar) / fstar;
  const double gap_newton = (newton.cost - fstar) / fstar;
  EXPECT_GT(gap_plain, 1e-6) << "the chain should be slow for the rounds";
  EXPECT_LT(std::abs(gap_newton), 1e-8) << "plain " << gap_plain;
  EXPECT_LT(newton.grad_norm, plain.grad_norm);
  EXPECT_EQ(newton.relaxation_cost, n.cost);
}

// Two refinements that take the same Newton steps to the same cost: the same interface, steps,
// CG iterations, interface factorizations, neighbour exchanges and shipped solutions (what rides
// in which message may differ).
void expect_same_steps(const NewtonRefineResult& x, const NewtonRefineResult& y) {
  EXPECT_EQ(y.interface_coordinates, x.interface_coordinates);
  EXPECT_EQ(y.steps, x.steps);
  EXPECT_EQ(y.accepted_steps, x.accepted_steps);
  EXPECT_EQ(y.cg_iterations, x.cg_iterations);
  EXPECT_EQ(y.interface_factorizations, x.interface_factorizations);
  EXPECT_EQ(y.exchanges, x.exchanges);
  EXPECT_EQ(y.solution_steps, x.solution_steps);
  EXPECT_EQ(y.cost, x.cost);
}

// NewtonRefineOptions::interface_in_status: the start point's interface shares ride in its
// status sum, so the refinement takes the same steps to the same bits in one message step
// fewer, whether every agent factors Sigma or agent 0 alone solves with it (its brief shares to
// the others).
TEST(NewtonRefine, TheStartPointsInterfaceSharesInItsStatusSumSaveAMessageStepForTheSameSteps) {
  const PoseGraph g = long_chain();
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  using SigmaFactoring = NewtonRefineOptions::SigmaFactoring;
  for (const SigmaFactoring sigma : {SigmaFactoring::kEveryAgent, SigmaFactoring::kShipSolves}) {
    DistributedOptions on = refined(true);
    on.refine.sigma_factoring = sigma;
    on.refine.ship_solves_min_coordinates = 0;  // the chain's interface is small
    DistributedOptions off = on;
    off.refine.interface_in_status = false;
    const DistributedResult a = solve_distributed(g, parts, off);
    const DistributedResult b = solve_distributed(g, parts, on);
    ASSERT_EQ(a.refines.size(), 1u);
    ASSERT_EQ(b.refines.size(), 1u);
    const NewtonRefineResult &x = a.refines[0], &y = b.refines[0];
    ASSERT_GT(x.interface_coordinates, 0) << "the chain's refinement should use interface solves";
    expect_same_steps(x, y);
    EXPECT_EQ(y.reductions, x.reductions - 1);
    EXPECT_EQ(y.message_steps(), x.message_steps() - 1);
    EXPECT_EQ(b.X, a.X);
  }
}

// NewtonRefineOptions::interface_in_trial_sums: a trial predicted not to end the refinement
// carries each block's interface share at the trial point in its sum, so an accepted one's CG
// starts without an interface step: the same steps to the same bits, one message step fewer
// per such step, whether every agent factors Sigma or agent 0 alone solves with it.
TEST(NewtonRefine, AnAcceptedTrialsInterfaceSharesInItsSumSaveAMessageStepForTheSameSteps) {
  const PoseGraph g = long_chain();
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  using SigmaFactoring = NewtonRefineOptions::SigmaFactoring;
  for (const SigmaFactoring sigma : {SigmaFactoring::kEveryAgent, SigmaFactoring::kShipSolves}) {
    DistributedOptions on = refined(true);
    on.refine.sigma_factoring = sigma;
    on.refine.ship_solves_min_coordinates = 0;  // the chain's interface is small
    DistributedOptions off = on;
    off.refine.interface_in_trial_sums = false;
    const DistributedResult a = solve_distributed(g, parts, off);
    const DistributedResult b = solve_distributed(g, parts, on);
    ASSERT_EQ(a.refines.size(), 1u);
    ASSERT_EQ(b.refines.size(), 1u);
    const NewtonRefineResult &x = a.refines[0], &y = b.refines[0];
    ASSERT_GT(x.interface_coordinates, 0) << "the chain's refinement should use interface solves";
    ASSERT_GE(x.accepted_steps, 2) << "a step after an accepted one should run";
    EXPECT_EQ(x.interface_shares_carried, 0);
    EXPECT_GE(y.interface_shares_carried, 1);
    expect_same_steps(x, y);
    EXPECT_EQ(y.reductions, x.reductions - y.interface_shares_carried);
    EXPECT_EQ(b.X, a.X);
  }
}

// Exact trial translations with one factor of their Sigma (translation_one_factor_min_poses):
// agent 0 alone factors it and sends every agent u, so each trial costs one more message step
// and the run is the same to the bit as every agent factoring it; in any delivery order too.
TEST(NewtonRefine, OneTranslationSigmaFactorGivesTheSameRunToTheBitInOneMoreStepATrial) {
  const PoseGraph g = long_chain();
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  DistributedOptions every = refined(true);
  every.refine.translation_one_factor_min_poses = 1000000;
  DistributedOptions one = every;
  one.refine.translation_one_factor_min_poses = 0;
  const DistributedResult a = solve_distributed(g, parts, every);
  const DistributedResult b = solve_distributed(g, parts, one);
  ASSERT_EQ(a.refines.size(), 1u);
  ASSERT_EQ(b.refines.size(), 1u);
  const NewtonRefineResult &x = a.refines[0], &y = b.refines[0];
  ASSERT_GT(x.translation_solves, 0) << "the chain's trials should use exact translations";
  EXPECT_EQ(x.translation_solutions_received, 0);
  EXPECT_EQ(y.translation_solutions_received, y.translation_solves);
  expect_same_steps(x, y);
  EXPECT_EQ(y.translation_solves, x.translation_solves);
  EXPECT_EQ(y.reductions, x.reductions + y.translation_solves);
  EXPECT_EQ(b.X, a.X);
  EXPECT_EQ(b.cost, a.cost);
  const std::vector<int> three = sequential_partition(g.num_poses, 3);
  test::expect_same_refinement_in_any_delivery_order(g, three, one, 11);
}

TEST(NewtonRefine, EveryAgentTakesTheSameStepsInAnyDeliveryOrder) {
  const PoseGraph g = long_chain();
  const std::vector<int> parts = sequential_partition(g.num_poses, 3);
  test::expect_same_refinement_in_any_delivery_order(g, parts, refined(true), 11);
}

TEST(NewtonRefine, RunsAfterEachSolveStageOfTheCertifiedSequenceAndKeepsTheCertificate) {
  const PoseGraph g = long_chain();
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  DistributedOptions o = refined(true);
  o.certify = true;
  const DistributedResult r = solve_distributed(g, parts, o);
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_TRUE(*r.certified);
  EXPECT_EQ(r.refines.size(), r.certificates.size());  // one solve stage per certificate here
  EXPECT_EQ(r.relaxation_cost, r.refines.back().cost);
}

TEST(NewtonRefine, IsNotRunAfterASolveOutOfRounds) {
  const PoseGraph g = long_chain();
  DistributedOptions o = refined(true);
  o.max_rounds = 2;
  o.grad_norm_tol = 1e-9;
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 3), o);
  EXPECT_EQ(r.stop_reason, "max_rounds");
  EXPECT_TRUE(r.refines.empty());
}

// On the same block states (as an online run keeps them): rounds to a gradient of 1, then
// Newton steps alone to 1e-2, then on to 1e-6 from there. Returns each block's tangent
// factorizations after each of the three solves, and the final cost.
struct ThreeSolves {
  std::vector<std::vector<int>> factorizations;
  double cost = 0.0;
};

ThreeSolves rounds_then_refine_twice(bool refactor_every_step) {
  const PoseGraph g = long_chain();
  LiveBlocks live(3, BlockUpdateOptions{}, 0.0);
  live.sync(g, sequential_partition(g.num_poses, 4), lift_poses(chordal_initialization(g), 5));
  DistributedOptions o;
  o.round_result = false;
  o.grad_norm_tol = 1.0;
  set_refine_mode(o.refine, "none");  // the first solve: rounds alone
  ThreeSolves out;
  for (double tol : {0.0, 1e-2, 1e-6}) {
    if (tol > 0) {
      o.grad_norm_tol = 1e300;  // no round: the refinement from where the last solve stopped
      set_refine_mode(o.refine, "newton");
      o.refine.grad_norm_tol = tol;
      o.refine.relative_decrease_tol = 0.0;
      o.refine.refactor_every_step = refactor_every_step;
      // Block Jacobi's factors are the subject (the interface solves factor their own).
      o.refine.interface_max_coordinates = 0;
    }
    const DistributedResult r =
        solve_distributed_with_states(live.graph(), live.layout(), live.all_states(), o);
    if (tol > 0) {
      EXPECT_EQ(r.rounds, 0);
      EXPECT_LE(r.grad_norm, tol);
      EXPECT_GE(r.refines.at(0).accepted_steps, 1);
    }
    out.factorizations.emplace_back();
    for (const AgentState* s : live.all_states())
      out.factorizations.back().push_back(s->tangent_factorizations());
    out.cost = r.relaxation_cost;
  }
  return out;
}

TEST(NewtonRefine, WithoutRefactoringEveryStepABlockKeepsTheFactorItHolds) {
  // The online steps' setting: a block that holds a factor (from the rounds) keeps it through
  // later refinements on the same problem (the point moved, the data did not).
  const ThreeSolves kept = rounds_then_refine_twice(false);
  for (std::size_t b = 0; b < 4; ++b) {
    EXPECT_GE(kept.factorizations[0][b], 1) << b;
    EXPECT_EQ(kept.factorizations[1][b], kept.factorizations[0][b]) << b;
    EXPECT_EQ(kept.factorizations[2][b], kept.factorizations[0][b]) << b;
  }
  // Refactoring at every step: at the start of each refinement and after each accepted step
  // that is followed by another CG; the same optimum either way.
  const ThreeSolves fresh = rounds_then_refine_twice(true);
  for (std::size_t b = 0; b < 4; ++b) {
    EXPECT_GT(fresh.factorizations[1][b], fresh.factorizations[0][b]) << b;
    EXPECT_GT(fresh.factorizations[2][b], fresh.factorizations[1][b]) << b;
  }
  EXPECT_NEAR(kept.cost, fresh.cost, 1e-9 * fresh.cost);
}

// A 2D corridor walked out and back (a U, 1 m steps, the legs 10 m apart) with loop closures
// between the legs: like ais2klinik, a Newton step from where the rounds stop bends it, turning
// long pieces of it about points hundreds of metres away.
PoseGraph corridor(int leg, int closures, double rotation_noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Pose> truth;
  for (int k = 0; k < 2 * leg; ++k) {
    Pose p;
    const bool out = k < leg;
    const double theta = out ? 0.0 : M_PI;
    p.R = Eigen::Rotation2Dd(theta).toRotationMatrix();
    p.t = out ? Eigen::Vector2d(static_cast<double>(k), 0.0)
              : Eigen::Vector2d(static_cast<double>(2 * leg - 1 - k), 10.0);
    truth.push_back(p);
  }
  PoseGraph g;
  g.d = 2;
  g.num_poses = truth.size();
  auto add = [&](std::size_t i, std::size_t j) {
    Measurement m;
    m.i = i;
    m.j = j;
    const Eigen::Matrix2d Rij = truth[i].R.transpose() * truth[j].R;
    m.R = Rij * Eigen::Rotation2Dd(rotation_noise * noise(rng)).toRotationMatrix();
    m.t = truth[i].R.transpose() * (truth[j].t - truth[i].t) +
          0.05 * Eigen::Vector2d(noise(rng), noise(rng));
    m.kappa = 1000.0;
    m.tau = 10.0;
    g.measurements.push_back(m);
  };
  for (std::size_t k = 0; k + 1 < truth.size(); ++k) add(k, k + 1);
  for (int c = 1; c <= closures; ++c) {
    const int a = c * leg / (closures + 1);
    add(static_cast<std::size_t>(a), static_cast<std::size_t>(2 * leg - 1 - a));
  }
  return g;
}

// The corridor of 500 poses (3 closures) in 5 sequential blocks, solved and refined twice: a
// with `options`, b with `vary` applied to them. Each has one refinement, and both reach the
// corridor's optimum.
struct CorridorTwoWays {
  PoseGraph g;
  std::vector<int> parts;
  DistributedOptions options;
  DistributedResult a, b;
};
void refine_corridor_two_ways(const DistributedOptions& options, void (*vary)(NewtonRefineOptions&),
                              CorridorTwoWays& out) {
  out.g = corridor(500, 3, 0.1, 7);
  out.parts = sequential_partition(out.g.num_poses, 5);
  const double fstar = test::tight_optimum(out.g);
  out.options = options;
  DistributedOptions varied = options;
  vary(varied.refine);
  out.a = solve_distributed(out.g, out.parts, out.options);
  out.b = solve_distributed(out.g, out.parts, varied);
  ASSERT_EQ(out.a.refines.size(), 1u);
  ASSERT_EQ(out.b.refines.size(), 1u);
  EXPECT_LT(std::abs(out.a.cost - fstar) / fstar, 1e-8);
  EXPECT_LT(std::abs(out.b.cost - fstar) / fstar, 1e-8);
}

// The trial point's translations re-solved for its rotations by the block-Jacobi CG: from the
// same point the same CG step is tried, and its trial lowers f at least as much as the
// retraction alone (CG on the convex quadratic in the translations lowers f at every
// iteration), so the trust region is cut less; both reach the optimum.
TEST(NewtonRefine, TrialTranslationsReSolvedLowerTheTrialCostAndReachTheOptimum) {
  DistributedOptions with = refined(true);
  with.grad_norm_tol = 10.0;
  with.refine.translation_interface_max_poses = 0;  // the CG
  CorridorTwoWays run;                              // a with the translation solves, b without
  ASSERT_NO_FATAL_FAILURE(refine_corridor_two_ways(
      with, [](NewtonRefineOptions& r) { r.translation_iterations = 0; }, run));
  const NewtonRefineResult& ra = run.a.refines[0];
  const NewtonRefineResult& rb = run.b.refines[0];
  EXPECT_EQ(rb.translation_iterations, 0);
  EXPECT_GE(ra.translation_iterations, ra.steps);
  ASSERT_FALSE(ra.trace.empty());
  ASSERT_FALSE(rb.trace.empty());
  EXPECT_EQ(ra.trace[0].cg_iterations, rb.trace[0].cg_iterations);
  EXPECT_EQ(ra.trace[0].predicted, rb.trace[0].predicted);
  EXPECT_GT(ra.trace[0].translation_iterations, 0);
  EXPECT_GT(ra.trace[0].actual, rb.trace[0].actual);
  for (const NewtonRefineStep& t : ra.trace) {
    if (t.accepted) {
      EXPECT_GT(t.actual, 0.0);
    }
  }
}

// Exact trial translations (NewtonRefineOptions::translation_interface_max_poses): the trial's
// translations are the exact minimiser for its rotations, so its cost is at most the CG's
// (which stops short of it) from the same CG step; the same optimum in fewer message steps,
// with no translation CG at all. A cap below the team's interface is the CG run exactly.
TEST(NewtonRefine, ExactTrialTranslationsReachTheCgOptimumInFewerMessageSteps) {
  DistributedOptions exact = refined(true);
  exact.grad_norm_tol = 10.0;
  CorridorTwoWays run;  // a with exact trial translations, b with the CG
  ASSERT_NO_FATAL_FAILURE(refine_corridor_two_ways(
      exact, [](NewtonRefineOptions& r) { r.translation_interface_max_poses = 0; }, run));
  const NewtonRefineResult& ra = run.a.refines[0];
  const NewtonRefineResult& rb = run.b.refines[0];
  // A U of 1,000 poses in 5 pieces with 3 closures: a few interface poses a block.
  EXPECT_GT(ra.translation_interface_poses, 0);
  EXPECT_LE(ra.translation_interface_poses, 20);
  EXPECT_EQ(ra.translation_iterations, 0);
  EXPECT_EQ(ra.translation_solves, ra.steps);
  EXPECT_EQ(rb.translation_interface_poses, 0);
  EXPECT_EQ(rb.translation_solves, 0);
  EXPECT_GE(rb.translation_iterations, rb.steps);
  ASSERT_FALSE(ra.trace.empty());
  ASSERT_FALSE(rb.trace.empty());
  EXPECT_EQ(ra.trace[0].cg_iterations, rb.trace[0].cg_iterations);
  EXPECT_EQ(ra.trace[0].predicted, rb.trace[0].predicted);
  EXPECT_GE(ra.trace[0].actual, rb.trace[0].actual - 1e-12 * std::abs(ra.initial_cost));
  // Here the same steps (5) and CG iterations: one sum a trial point in place of the CG's
  // 21 iterations (two message steps each) and the re-solved translations' exchange.
  EXPECT_LT(ra.exchanges + ra.reductions, rb.exchanges + rb.reductions);
  DistributedOptions capped = exact;
  capped.refine.translation_interface_max_poses = ra.translation_interface_poses - 1;
  const DistributedResult c = solve_distributed(run.g, run.parts, capped);
  ASSERT_EQ(c.refines.size(), 1u);
  EXPECT_EQ(c.refines[0].translation_interface_poses, 0);
  EXPECT_EQ(c.refines[0].translation_iterations, rb.translation_iterations);
  EXPECT_EQ(c.refines[0].exchanges, rb.exchanges);
  EXPECT_EQ(c.cost, run.b.cost);
}

// Interface solves (NewtonRefineOptions::interface_max_coordinates): with each block's
// Hessian factored exactly and the interface's Schur complement solved by every agent, the
// preconditioner is the Hessian's inverse (up to the gauge shift), so a Newton step's CG ends
// in a few iterations where block Jacobi needs dozens; the same optimum either way.
TEST(NewtonRefine, InterfaceSolvesReachTheBlockJacobiOptimumInFewerCgIterations) {
  DistributedOptions exact = refined(true);
  exact.grad_norm_tol = 1.0;
  CorridorTwoWays run;  // a with the interface solves, b block Jacobi
  ASSERT_NO_FATAL_FAILURE(refine_corridor_two_ways(
      exact, [](NewtonRefineOptions& r) { r.interface_max_coordinates = 0; }, run));
  const NewtonRefineResult& ra = run.a.refines[0];
  const NewtonRefineResult& rb = run.b.refines[0];
  EXPECT_EQ(rb.interface_coordinates, 0);
  EXPECT_EQ(rb.interface_factorizations, 0);
  // 4 cut edges in a chain of 5 blocks plus the closures' cuts: a few poses a block.
  EXPECT_GT(ra.interface_coordinates, 0);
  EXPECT_LE(ra.interface_coordinates, 3 * 20);
  EXPECT_GE(ra.interface_factorizations, 1);
  EXPECT_LE(ra.interface_factorizations, ra.accepted_steps + 1);
  EXPECT_EQ(ra.interface_fallbacks, 0);
  // Exact solves: each Newton step's CG stops on its residual within a few iterations.
  for (const NewtonRefineStep& t : ra.trace)
    if (t.cg_stop == "residual") {
      EXPECT_LE(t.cg_iterations, 3);
    }
  EXPECT_LT(3 * ra.cg_iterations, rb.cg_iterations);
  // A cap below the team's interface leaves block Jacobi (the same run as without).
  DistributedOptions capped = exact;
  capped.refine.interface_max_coordinates = ra.interface_coordinates - 1;
  const DistributedResult c = solve_distributed(run.g, run.parts, capped);
  ASSERT_EQ(c.refines.size(), 1u);
  EXPECT_EQ(c.refines[0].interface_coordinates, 0);
  EXPECT_EQ(c.refines[0].cg_iterations, rb.cg_iterations);
  EXPECT_EQ(c.cost, run.b.cost);
}

// The interface solves' decisions (Sigma's factorization, its shift, the fallback) are taken
// from the same shares in agent-id order by every agent: the same steps in any delivery order.
TEST(NewtonRefine, InterfaceSolvesTakeTheSameStepsInAnyDeliveryOrder) {
  const PoseGraph g = corridor(300, 2, 0.1, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  DistributedOptions o = refined(true);
  o.grad_norm_tol = 1.0;
  const DistributedResult r = test::expect_same_refinement_in_any_delivery_order(g, parts, o, 5);
  ASSERT_EQ(r.refines.size(), 1u);
  EXPECT_GE(r.refines[0].interface_factorizations, 1);
}

// A geometric tail c_k = f + a q^k: the estimate from two windows is the exact cost still to
// come; a flat one 0.
TEST(RoundsTail, AGeometricTailIsEstimatedExactly) {
  std::vector<RoundRecord> trace;
  const double f = 100.0, a = 0.5, q = 0.8;
  for (int k = 0; k <= 30; ++k) {
    RoundRecord r;
    r.round = k;
    r.cost = f + a * std::pow(q, k);
    trace.push_back(r);
  }
  const double gap = a * std::pow(q, 30) / trace.back().cost;
  EXPECT_NEAR(rounds_tail_gap(trace, 5, 0.99), gap, 1e-9 * gap);  // round-off of 100 + a q^k
  // A rate above the cap is read as the cap: q^5 = 0.33 > 0.2.
  const double d1 = trace[25].cost - trace[30].cost;
  EXPECT_NEAR(rounds_tail_gap(trace, 5, 0.2), d1 * 0.2 / 0.8 / trace[30].cost, 1e-12);
  for (auto& r : trace) r.cost = f;
  EXPECT_EQ(rounds_tail_gap(trace, 5, 0.9), 0.0);
}

// Fewer records than two windows: the last half's decrease at the capped rate, above the true
// tail of a geometric one (its own rate, 0.8 here, is not read from so few rounds); no round
// at all: nothing to go by, 0.
TEST(RoundsTail, AShortTraceIsReadAtTheCappedRateAndNoRoundGivesZero) {
  const double f = 100.0, a = 0.5, q = 0.8;
  std::vector<RoundRecord> trace;
  for (int k = 0; k <= 8; ++k) {  // 8 rounds, 9 records: shorter than 2 x 5 + 1
    RoundRecord r;
    r.round = k;
    r.cost = f + a * std::pow(q, k);
    trace.push_back(r);
  }
  const double d = trace[4].cost - trace[8].cost;  // the last 4 rounds
  const double estimate = rounds_tail_gap(trace, 5, 0.9);
  EXPECT_NEAR(estimate, d * 9.0 / trace[8].cost, 1e-12);
  EXPECT_GT(estimate, a * std::pow(q, 8) / trace[8].cost);  // the true tail
  const std::vector<RoundRecord> one_round(trace.begin(), trace.begin() + 2);
  EXPECT_NEAR(rounds_tail_gap(one_round, 5, 0.9),
              (trace[0].cost - trace[1].cost) * 9.0 / trace[1].cost, 1e-12);
  const std::vector<RoundRecord> start_only(trace.begin(), trace.begin() + 1);
  EXPECT_EQ(rounds_tail_gap(start_only, 5, 0.9), 0.0);
}

// `--refine auto`: the long chain's rounds stop 1.5e-5 above f* with the cost still falling,
// so the refinement runs and ends at f*; asked for a gap the tail does not reach, it does not
// run and the rounds' answer stands.
TEST(NewtonRefine, AutoRefinesOnlyWhereTheRoundsTailSaysTheyStoppedShort) {
  const PoseGraph g = long_chain();
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  const double fstar = test::tight_optimum(g);
  DistributedOptions autoo = refined(true);
  autoo.refine.when = NewtonRefineOptions::When::kIfRoundsSlow;
  autoo.refine.auto_interface_grad_tol = 0;  // the tail alone decides (no early hand-over)
  const DistributedResult a = solve_distributed(g, parts, autoo);
  ASSERT_EQ(a.refines.size(), 1u);
  EXPECT_LT(std::abs(a.cost - fstar) / fstar, 1e-8);
  DistributedOptions loose = autoo;
  loose.refine.auto_gap_tol = 1.0;
  const DistributedResult b = solve_distributed(g, parts, loose);
  const DistributedResult plain = solve_distributed(g, parts, refined(false));
  EXPECT_TRUE(b.refines.empty());
  EXPECT_EQ(b.cost, plain.cost);
  EXPECT_EQ(b.rounds, a.rounds);
}

TEST(NewtonRefineOptions, ValidateNamesTheBadField) {
  NewtonRefineOptions o;
  EXPECT_EQ(test::validation_message(o), "");
  o.grad_norm_tol = 0;
  EXPECT_TRUE(test::validation_names(o, "grad_norm_tol"));
  o = {};
  o.max_cg_iterations = 0;
  EXPECT_TRUE(test::validation_names(o, "max_cg_iterations"));
  o = {};
  o.forcing = 1.0;
  EXPECT_TRUE(test::validation_names(o, "forcing"));
  o = {};
  o.coarse_keep_steps = 0;
  EXPECT_TRUE(test::validation_names(o, "coarse_keep_steps"));
  o = {};
  o.auto_gap_tol = 0;
  EXPECT_TRUE(test::validation_names(o, "auto_gap_tol"));
  o = {};
  o.auto_window = 0;
  EXPECT_TRUE(test::validation_names(o, "auto_window"));
  o = {};
  o.translation_iterations = -1;
  EXPECT_TRUE(test::validation_names(o, "translation_iterations"));
  o = {};
  o.translation_interface_max_poses = -1;
  EXPECT_TRUE(test::validation_names(o, "translation_interface_max_poses"));
  o = NewtonRefineOptions{};
  o.translation_one_factor_min_poses = -1;
  EXPECT_TRUE(test::validation_names(o, "translation_one_factor_min_poses"));
  o = {};
  o.translation_tol = 0;
  EXPECT_TRUE(test::validation_names(o, "translation_tol"));
  o = {};
  o.relative_decrease_tol = -1;
  EXPECT_TRUE(test::validation_names(o, "relative_decrease_tol"));
  o = {};
  o.interface_max_coordinates = -1;
  EXPECT_TRUE(test::validation_names(o, "interface_max_coordinates"));
  o = {};
  o.interface_shift = 0;
  EXPECT_TRUE(test::validation_names(o, "interface_shift"));
  o = {};
  o.accept_ratio = 0.5;
  EXPECT_TRUE(test::validation_names(o, "accept_ratio"));
  DistributedOptions d;
  d.refine.enabled = true;
  d.refine.max_steps = 0;
  EXPECT_THROW(d.validate(), InputError);
}

// The interface solves hold the gauge fixed at one pose (interface_solve.hpp) and the step is
// tried without its gauge part (gauge_space.hpp). With Sigma shifted instead, the
// preconditioner multiplied the residual's round-off along the gauge by up to 1 / shift: on
// this 4,000-pose corridor, from |grad f| 3.8e-6 on, CG steps were global turns whose model
// promised 1.6e-7 where f gained 6.5e-11, 9 of 22 steps were rejected and |grad f| stayed at
// 4e-7. Now every step from |grad f| below 0.01 is accepted, its model within 1 % of f.
TEST(NewtonRefine, InterfaceSolveStepsNearTheOptimumAreAcceptedAsTheirModelPredicts) {
  const PoseGraph g = corridor(2000, 3, 0.1, 7);
  const std::vector<int> parts = sequential_partition(g.num_poses, 5);
  DistributedOptions o = refined(true);
  o.grad_norm_tol = 30.0;
  o.refine.grad_norm_tol = 1e-9;
  o.refine.relative_decrease_tol = 0.0;  // to round-off: only a step that lowers f by nothing
  const DistributedResult r = solve_distributed(g, parts, o);
  ASSERT_EQ(r.refines.size(), 1u);
  const NewtonRefineResult& n = r.refines[0];
  EXPECT_GT(n.interface_coordinates, 0);
  EXPECT_EQ(n.interface_fallbacks, 0);
  double gnorm = n.initial_grad_norm;
  int near = 0;
  for (const NewtonRefineStep& t : n.trace) {
    if (gnorm < 1e-2 && t.predicted > 1e-12 * std::abs(n.initial_cost)) {
      ++near;
      EXPECT_TRUE(t.accepted) << "at |grad f| " << gnorm;
      EXPECT_NEAR(t.actual, t.predicted, 0.01 * t.predicted) << "at |grad f| " << gnorm;
    }
    gnorm = t.grad_norm;
  }
  EXPECT_GE(near, 2);
  EXPECT_LT(n.grad_norm, 1e-8);
}

}  // namespace
}  // namespace tessera

namespace tessera {
namespace {

// The interface solves' CG on the tangent vectors orthogonal to the gauge
// (NewtonRefineOptions::project_gauge) against the grounded pose held, from a rough start (the
// rounds stop at gradient 30) on the 1,000-pose corridor: the grounded CG meets negative
// curvature along the gauge (a global turn about the held pose) on its first step, whose trial
// raises f, and takes 6 steps (one rejected); the projected one sees none, every step is
// accepted, in fewer steps and message steps; the same optimum, no fallback.
TEST(NewtonRefine, ProjectedGaugeCgMeetsNoSpuriousNegativeCurvatureFromARoughStart) {
  const PoseGraph g = corridor(500, 3, 0.1, 7);
  const std::vector<int> parts = sequential_partition(g.num_poses, 5);
  const double fstar = test::tight_optimum(g);
  DistributedOptions o = refined(true);
  o.grad_norm_tol = 30.0;
  DistributedOptions p = o;
  p.refine.project_gauge = true;
  const DistributedResult a = solve_distributed(g, parts, o);
  const DistributedResult b = solve_distributed(g, parts, p);
  ASSERT_EQ(a.refines.size(), 1u);
  ASSERT_EQ(b.refines.size(), 1u);
  for (const DistributedResult* r : {&a, &b}) {
    const NewtonRefineResult& n = r->refines[0];
    EXPECT_GT(n.interface_coordinates, 0);
    EXPECT_EQ(n.interface_fallbacks, 0);
    EXPECT_LT(std::abs(r->cost - fstar) / fstar, 1e-8);
  }
  const NewtonRefineResult& ground = a.refines[0];
  const NewtonRefineResult& projected = b.refines[0];
  ASSERT_FALSE(ground.trace.empty());
  EXPECT_EQ(ground.trace[0].cg_stop, "negative_curvature");
  EXPECT_FALSE(ground.trace[0].accepted);
  for (const NewtonRefineStep& t : projected.trace) {
    EXPECT_NE(t.cg_stop, "negative_curvature");
    EXPECT_TRUE(t.accepted);
  }
  EXPECT_LT(projected.steps, ground.steps);
  EXPECT_LT(projected.exchanges + projected.reductions, ground.exchanges + ground.reductions);
  // Each agent's timers (NewtonRefineTimes): every moment charged to one part, and the interface
  // solves' factorizations and Sigma among them.
  const NewtonRefineTimes& t = ground.times;
  EXPECT_NEAR(t.cpu_s, t.setup_s + t.factor_s + t.sigma_s + t.cg_s + t.trial_s + t.translations_s,
              1e-9);
  EXPECT_GT(t.factor_s, 0.0);
  EXPECT_GT(t.sigma_s, 0.0);
  EXPECT_GT(t.wall_s, 0.0);  // set where the refinement ends
}

}  // namespace
}  // namespace tessera

namespace tessera {
namespace {

// The corridor's poses composed along its odometry: every step's rotation noise adds up, so
// the legs start bent far from the optimum, where Hess f is indefinite.
std::vector<Pose> composed_odometry(const PoseGraph& g) {
  std::vector<Pose> poses(g.num_poses);
  poses[0].R = Eigen::Matrix2d::Identity();
  poses[0].t = Eigen::Vector2d::Zero();
  for (const Measurement& m : g.measurements) {
    if (m.j != m.i + 1) continue;
    poses[m.j].R = poses[m.i].R * m.R;
    poses[m.j].t = poses[m.i].t + poses[m.i].R * m.t;
  }
  return poses;
}

// Truncated CG that meets negative curvature follows the direction to the trust region's
// boundary, as one stopped by the boundary does: the step is as long as the radius, and where f
// falls as the model predicts (ratio above 3/4) the next step's radius is twice as large. From
// the composed odometry the first CG meets negative curvature at its second iteration and f
// falls by 1.04e6 where the model predicted 1.01e6. Were only the "boundary" stop counted as
// cut by the region, the radius would stay where such a step left it.
TEST(NewtonRefine, ANegativeCurvatureStepOnTheBoundaryThatLowersFAsPredictedDoublesTheRadius) {
  const PoseGraph g = corridor(500, 3, 0.05, 7);
  const std::vector<int> parts = sequential_partition(g.num_poses, 5);
  DistributedOptions o = refined(true);
  o.grad_norm_tol = 1e300;  // no round: the Newton steps from the composed odometry
  o.refine.grad_norm_tol = 1e-6;
  const DistributedResult r = solve_distributed(g, parts, o, composed_odometry(g));
  ASSERT_EQ(r.refines.size(), 1u);
  const std::vector<NewtonRefineStep>& trace = r.refines[0].trace;
  int doubled = 0;
  for (std::size_t k = 0; k < trace.size(); ++k) {
    const NewtonRefineStep& t = trace[k];
    if (t.cg_stop != "negative_curvature") continue;
    EXPECT_NEAR(t.step_norm, t.radius, 1e-9 * t.radius) << "step " << k;
    if (t.accepted && t.actual > 0.8 * t.predicted && k + 1 < trace.size()) {
      EXPECT_EQ(trace[k + 1].radius, 2.0 * t.radius) << "step " << k;
      ++doubled;
    }
  }
  EXPECT_GE(doubled, 1);
}

}  // namespace
}  // namespace tessera
