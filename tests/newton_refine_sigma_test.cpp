// Who factors the refinement's interface matrix Sigma: every agent at every point; agent 0
// alone, sending its factor to the others (NewtonRefineOptions::SigmaFactoring::kShipFactor); or
// agent 0 alone, sending each agent its segment of every solve (kShipSolves). All three take the
// same steps and CG iterations to the same bits.

#include <gtest/gtest.h>

#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/distributed/newton_refine.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <vector>

#include "refine_harness.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

using SigmaFactoring = NewtonRefineOptions::SigmaFactoring;

DistributedOptions refined(SigmaFactoring sigma) {
  DistributedOptions o;
  o.grad_norm_tol = 0.01;
  set_refine_mode(o.refine, "newton");
  o.refine.sigma_factoring = sigma;
  o.refine.ship_solves_min_coordinates = 0;  // the chain's interface is small
  return o;
}

// `other`'s refinement (the only one of its run) takes `every`'s steps, CG iterations and
// exchanges to the same bits: cost and every pose.
void expect_same_refinement(const DistributedResult& every, const DistributedResult& other) {
  ASSERT_EQ(every.refines.size(), 1u);
  ASSERT_EQ(other.refines.size(), 1u);
  const NewtonRefineResult &a = every.refines[0], &b = other.refines[0];
  ASSERT_GT(a.interface_coordinates, 0) << "the chain's refinement should use interface solves";
  EXPECT_EQ(b.steps, a.steps);
  EXPECT_EQ(b.accepted_steps, a.accepted_steps);
  EXPECT_EQ(b.cg_iterations, a.cg_iterations);
  EXPECT_EQ(b.exchanges, a.exchanges);
  // Less the interface steps an accepted trial's sum carried (interface_in_trial_sums: not
  // where agent 0 ships its Sigma factor in that step).
  EXPECT_EQ(b.reductions + b.interface_shares_carried, a.reductions + a.interface_shares_carried);
  EXPECT_EQ(b.interface_factorizations, a.interface_factorizations);
  EXPECT_EQ(b.cost, a.cost);
  EXPECT_EQ(other.relaxation_cost, every.relaxation_cost);
  EXPECT_EQ(other.cost, every.cost);
  ASSERT_EQ(other.poses.size(), every.poses.size());
  for (std::size_t i = 0; i < other.poses.size(); ++i) {
    ASSERT_EQ(other.poses[i].R, every.poses[i].R) << "pose " << i;
    ASSERT_EQ(other.poses[i].t, every.poses[i].t) << "pose " << i;
  }
}

TEST(NewtonRefineSigma, AgentZeroFactoringSigmaTakesTheSameStepsAsEveryAgentFactoringIt) {
  const PoseGraph g = test::refine_chain(600, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  const DistributedResult every = solve_distributed(g, parts, refined(SigmaFactoring::kEveryAgent));
  const DistributedResult one = solve_distributed(g, parts, refined(SigmaFactoring::kShipFactor));
  expect_same_refinement(every, one);
  ASSERT_FALSE(HasFatalFailure());
  const NewtonRefineResult &a = every.refines[0], &b = one.refines[0];
  // Every agent factors at every point without shipping; with it, agent 0 (the one reported)
  // factors at every point too, and a point after the start takes the shipped path unless
  // its step was predicted to be the last. Either way a trial's block factor goes unused where
  // it was rejected or the refinement stopped there.
  EXPECT_EQ(a.sigma_factorizations, a.interface_factorizations);
  EXPECT_EQ(a.sigma_imports, 0);
  EXPECT_LE(a.pending_factors_unused, a.steps - a.accepted_steps + 1);
  EXPECT_EQ(b.interface_shares_carried, 0) << "agent 0's factor rides in the interface step";
  EXPECT_EQ(b.sigma_factorizations, b.interface_factorizations);
  EXPECT_EQ(b.sigma_imports, 0) << "agent 0 factors; the others take its factor";
  EXPECT_LE(b.pending_factors_unused, b.steps - b.accepted_steps + 1);
}

TEST(NewtonRefineSigma, EveryAgentTakesTheSameStepsInAnyDeliveryOrderWithSigmaShipped) {
  const PoseGraph g = test::refine_chain(600, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 3);
  test::expect_same_refinement_in_any_delivery_order(g, parts, refined(SigmaFactoring::kShipFactor),
                                                     7);
}

// kShipSolves (`--refine-sigma solve`): agent 0 alone assembles and factors Sigma and sends
// each agent its segment of every solve.
TEST(NewtonRefineSigma, OneAgentSolvingWithSigmaTakesTheSameStepsAsEveryAgentFactoringIt) {
  const PoseGraph g = test::refine_chain(600, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  const DistributedResult every = solve_distributed(g, parts, refined(SigmaFactoring::kEveryAgent));
  const DistributedResult solves =
      solve_distributed(g, parts, refined(SigmaFactoring::kShipSolves));
  expect_same_refinement(every, solves);
  ASSERT_FALSE(HasFatalFailure());
  const NewtonRefineResult &a = every.refines[0], &b = solves.refines[0];
  // One message step more for each CG direction (each iteration's and each step's first);
  // agent 0 (the one reported) holds Sigma at every point.
  EXPECT_EQ(a.solution_steps, 0);
  EXPECT_GE(b.solution_steps, b.cg_iterations);
  EXPECT_EQ(b.message_steps(), a.message_steps() + b.solution_steps);
  EXPECT_EQ(a.sigma_factorizations, a.interface_factorizations);
  EXPECT_EQ(b.sigma_factorizations, b.interface_factorizations);
  // The other agents receive only each share's flag and residuals, not its Schur complement.
  EXPECT_LT(solves.bytes_exchanged, every.bytes_exchanged);
}

TEST(NewtonRefineSigma, EveryAgentTakesTheSameStepsInAnyDeliveryOrderWithSigmaSolvesShipped) {
  const PoseGraph g = test::refine_chain(600, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 3);
  test::expect_same_refinement_in_any_delivery_order(g, parts, refined(SigmaFactoring::kShipSolves),
                                                     7);
}

// NewtonRefineOptions::analyses: a run that keeps its agents' interface factors between
// refinements analyses a pattern once; a refinement on a pattern its factors hold factors
// numerically only and takes the same steps to the same bits, one on another pattern analyses.
TEST(NewtonRefineSigma, ARefinementOnThePatternOfTheStoredFactorsSkipsTheirAnalysesToTheSameBits) {
  const PoseGraph g = test::refine_chain(600, 3), h = test::refine_chain(480, 3);
  const std::vector<int> parts = sequential_partition(g.num_poses, 4);
  const std::vector<int> h_parts = sequential_partition(h.num_poses, 4);
  DistributedOptions o = refined(SigmaFactoring::kEveryAgent);
  const DistributedResult fresh = solve_distributed(g, parts, o);
  const DistributedResult h_fresh = solve_distributed(h, h_parts, o);
  ASSERT_EQ(fresh.refines.size(), 1u);
  ASSERT_EQ(h_fresh.refines.size(), 1u);
  // The block's factor and Sigma's, each analysed once in the refinement.
  EXPECT_GE(fresh.refines[0].interface_analyses, 2);
  o.refine.analyses = make_interface_analysis_store();
  const DistributedResult first = solve_distributed(g, parts, o);
  const DistributedResult again = solve_distributed(g, parts, o);
  const DistributedResult other = solve_distributed(h, h_parts, o);
  ASSERT_EQ(first.refines.size(), 1u);
  ASSERT_EQ(again.refines.size(), 1u);
  ASSERT_EQ(other.refines.size(), 1u);
  EXPECT_EQ(first.refines[0].interface_analyses, fresh.refines[0].interface_analyses);
  EXPECT_EQ(again.refines[0].interface_analyses, 0);
  EXPECT_EQ(other.refines[0].interface_analyses, h_fresh.refines[0].interface_analyses);
  expect_same_refinement(fresh, again);
  expect_same_refinement(h_fresh, other);
}

TEST(NewtonRefineSigma, RefineSigmaNamesTheThreeWaysAndSolveIsTheDefault) {
  EXPECT_EQ(sigma_mode(NewtonRefineOptions{}), "solve");
  NewtonRefineOptions m;
  for (const std::string mode : {"every", "one", "solve"}) {
    set_sigma_mode(m, mode);
    EXPECT_EQ(sigma_mode(m), mode);
  }
  EXPECT_NE(test::input_error_of([&m] { set_sigma_mode(m, "two"); }).find("--refine-sigma"),
            std::string::npos);
}

TEST(NewtonRefineSigma, AnUnknownSigmaFactoringNamesTheField) {
  NewtonRefineOptions o;
  o.sigma_factoring = static_cast<SigmaFactoring>(7);
  EXPECT_TRUE(test::validation_names(o, "NewtonRefineOptions.sigma_factoring"));
}

}  // namespace
}  // namespace tessera
