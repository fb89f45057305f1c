// The distributed Newton refinement (newton_refine.hpp): from where the block-coordinate rounds
// stop, it reaches the centralized optimum of a long chain (the case the rounds are slow on)
// in a few trust-region steps; every agent takes the same steps whatever the delivery order;
// its options refuse bad values by name.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/online/live_blocks.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/chordal_initialization.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

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
  o.refine.enabled = on;
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
  // Each CG iteration is one neighbour exchange and one all-agent sum; each step adds one of
  // each for its trial point, plus the start's sum, a step's last CG exchange and the coarse
  // matrix's sum at each new point.
  EXPECT_GE(n.exchanges, n.cg_iterations + n.steps);
  EXPECT_LE(n.exchanges, n.cg_iterations + 2 * n.steps);
  EXPECT_EQ(n.reductions, n.exchanges + 1 + n.coarse_assemblies);
  EXPECT_LE(n.coarse_assemblies, n.accepted_steps + 1);
  // The rounds stop measurably above f*; the refined estimate is at f*.
  const double gap_plain = (plain.cost - fstar) / fstar;
  const double gap_newton = (newton.cost - fstar) / fstar;
  EXPECT_GT(gap_plain, 1e-6) << "the chain should be slow for the rounds";
  EXPECT_LT(std::abs(gap_newton), 1e-8) << "plain " << gap_plain;
  EXPECT_LT(newton.grad_norm, plain.grad_norm);
  EXPECT_EQ(newton.relaxation_cost, n.cost);
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
  ThreeSolves out;
  for (double tol : {0.0, 1e-2, 1e-6}) {
    if (tol > 0) {
      o.grad_norm_tol = 1e300;  // no round: the refinement from where the last solve stopped
      o.refine.enabled = true;
      o.refine.grad_norm_tol = tol;
      o.refine.relative_decrease_tol = 0.0;
      o.refine.refactor_every_step = refactor_every_step;
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

TEST(NewtonRefineOptions, ValidateNamesTheBadField) {
  auto message = [](const NewtonRefineOptions& o) { return test::validation_message(o); };
  NewtonRefineOptions o;
  EXPECT_EQ(message(o), "");
  o.grad_norm_tol = 0;
  EXPECT_NE(message(o).find("grad_norm_tol"), std::string::npos);
  o = {};
  o.max_cg_iterations = 0;
  EXPECT_NE(message(o).find("max_cg_iterations"), std::string::npos);
  o = {};
  o.forcing = 1.0;
  EXPECT_NE(message(o).find("forcing"), std::string::npos);
  o = {};
  o.relative_decrease_tol = -1;
  EXPECT_NE(message(o).find("relative_decrease_tol"), std::string::npos);
  o = {};
  o.accept_ratio = 0.5;
  EXPECT_NE(message(o).find("accept_ratio"), std::string::npos);
  DistributedOptions d;
  d.refine.enabled = true;
  d.refine.max_steps = 0;
  EXPECT_THROW(d.validate(), InputError);
}

}  // namespace
}  // namespace tessera
