// The distributed rounding's exact translation solve through the team's interface
// (core/runtime/rounding_interface.cpp), in process (one thread per agent, no DDS), against
// core's round_solution (the direct solve) and the rounding's own CG:
//  - it gives the direct solve's poses and cost, pose 0 at the origin, in fewer message steps
//    than the CG (contiguous blocks, and a partition whose pose 0 is no interface pose of
//    block 0, so the shift to pose 0 comes from its owner);
//  - with the cap below the team's interface the CG runs, bit for bit as with the cap at 0.

#include <gtest/gtest.h>

#include <cstddef>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/problem/objective.hpp>
#include <vector>

#include "distributed/interface_poses.hpp"
#include "distributed/translation_interface_solve.hpp"
#include "rounding_threads.hpp"

namespace tessera::agent {
namespace {

// This file's grids (generator seed 5): grid_rounding_case (support/rounding_threads.hpp).
RoundingCase grid_case(std::size_t poses, int agents, int max_rounds, bool partitioned) {
  return grid_rounding_case(poses, agents, max_rounds, partitioned, 5);
}

Eigen::Index team_interface(const RoundingCase& c) {
  return interface_pose_count(
      make_block_layout(c.graph.num_poses, c.graph.measurements, c.assignment));
}

// Largest distance between the two roundings' positions, each in its own pose 0's frame.
double worst_position_gap(const std::vector<Pose>& a, const std::vector<Pose>& b) {
  double worst = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const Eigen::VectorXd pa = a[0].R.transpose() * (a[k].t - a[0].t);
    const Eigen::VectorXd pb = b[0].R.transpose() * (b[k].t - b[0].t);
    worst = std::max(worst, (pa - pb).norm());
  }
  return worst;
}

void expect_direct_solve(const RoundingCase& c) {
  const DistributedRoundingOptions defaults;
  const Rounded r = round_in_threads(c, defaults);
  ASSERT_TRUE(r.errors.empty()) << r.errors.front();
  EXPECT_EQ(r.interface_poses, static_cast<std::uint32_t>(team_interface(c)));
  EXPECT_EQ(r.iterations, 0u);
  EXPECT_LT(worst_position_gap(r.poses, c.solved.poses), 1e-9);
  EXPECT_NEAR(r.cost, c.solved.cost, 1e-12 * c.solved.cost);
  EXPECT_NEAR(evaluate_objective(c.graph, r.poses), c.solved.cost, 1e-12 * c.solved.cost);
  EXPECT_EQ(r.poses[0].t.norm(), 0.0) << "pose 0 sits at the origin, as round_solution puts it";
  // The CG to its residual stop from zero: the same poses, in more message steps.
  DistributedRoundingOptions cg;
  cg.interface_max_poses = 0;
  cg.warm_start = false;
  cg.settle_tolerance = 0;
  const Rounded e = round_in_threads(c, cg);
  ASSERT_TRUE(e.errors.empty()) << e.errors.front();
  EXPECT_EQ(e.interface_poses, 0u);
  EXPECT_LT(worst_position_gap(r.poses, e.poses), 1e-9);
  EXPECT_LT(r.steps, e.steps) << "interface " << r.steps << " steps, CG " << e.steps;
}

TEST(RoundingInterface, ContiguousBlocksGetTheDirectSolvesPosesAndCost) {
  expect_direct_solve(grid_case(600, 4, 20, false));
}

TEST(RoundingInterface, PartitionedBlocksGetTheDirectSolvesPosesAndCost) {
  const RoundingCase c = grid_case(600, 5, 20, true);
  // The case the shift is for: pose 0 is not the team's first interface pose (the one the
  // interface solve holds fixed), so its translation comes from its owner.
  const BlockLayout layout =
      make_block_layout(c.graph.num_poses, c.graph.measurements, c.assignment);
  ASSERT_FALSE(interface_poses(layout, 0).empty());
  EXPECT_NE(interface_poses(layout, 0).front(), 0u) << "the solve should not hold pose 0 itself";
  expect_direct_solve(c);
}

TEST(RoundingInterface, OneAgentFactoringSigmaGivesThePosesOfEveryAgentFactoringItBitForBit) {
  const RoundingCase c = grid_case(600, 5, 20, true);
  DistributedRoundingOptions one, every;
  one.interface_one_factor_min_poses = 0;
  every.interface_one_factor_min_poses = 1000000;
  const Rounded a = round_in_threads(c, one);
  const Rounded b = round_in_threads(c, every);
  ASSERT_TRUE(a.errors.empty()) << a.errors.front();
  ASSERT_TRUE(b.errors.empty()) << b.errors.front();
  EXPECT_EQ(a.interface_poses, static_cast<std::uint32_t>(team_interface(c)));
  EXPECT_EQ(b.interface_poses, a.interface_poses);
  EXPECT_EQ(a.steps, b.steps) << "the first agent's wait for the residuals is a step";
  EXPECT_EQ(a.cost, b.cost);
  for (std::size_t k = 0; k < a.poses.size(); ++k) {
    EXPECT_EQ(a.poses[k].R, b.poses[k].R) << "pose " << k;
    EXPECT_EQ(a.poses[k].t, b.poses[k].t) << "pose " << k;
  }
}

TEST(RoundingInterface, CapBelowTheTeamInterfaceRunsTheCgBitForBit) {
  const RoundingCase c = grid_case(600, 4, 20, false);
  const Eigen::Index team = team_interface(c);
  ASSERT_GT(team, 1);
  DistributedRoundingOptions capped, off;
  capped.interface_max_poses = static_cast<std::size_t>(team - 1);
  off.interface_max_poses = 0;
  const Rounded a = round_in_threads(c, capped);
  const Rounded b = round_in_threads(c, off);
  ASSERT_TRUE(a.errors.empty()) << a.errors.front();
  ASSERT_TRUE(b.errors.empty()) << b.errors.front();
  EXPECT_EQ(a.interface_poses, 0u);
  EXPECT_GT(a.iterations, 0u);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.cost, b.cost);
  for (std::size_t k = 0; k < a.poses.size(); ++k) {
    EXPECT_EQ(a.poses[k].R, b.poses[k].R) << "pose " << k;
    EXPECT_EQ(a.poses[k].t, b.poses[k].t) << "pose " << k;
  }
  // At the cap exactly, the interface solve runs.
  DistributedRoundingOptions at;
  at.interface_max_poses = static_cast<std::size_t>(team);
  const Rounded r = round_in_threads(c, at);
  ASSERT_TRUE(r.errors.empty()) << r.errors.front();
  EXPECT_EQ(r.interface_poses, static_cast<std::uint32_t>(team));
}

}  // namespace
}  // namespace tessera::agent
