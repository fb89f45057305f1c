// The partition follows the graph: border poses move out of over-full blocks, as few as the
// bound needs, and an online run whose robots grow unevenly still ends at the batch optimum.

#include <gtest/gtest.h>

#include <algorithm>
#include <tessera/generate/generator.hpp>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/solvers/centralized_solver.hpp>

#include "test_support.hpp"

namespace tessera {
namespace {

// A chain 0 - 1 - ... - n-1 (structure only: rebalancing reads endpoints).
PoseGraph chain(std::size_t n) {
  PoseGraph g;
  g.d = 2;
  g.num_poses = n;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    Measurement m;
    m.i = k;
    m.j = k + 1;
    g.measurements.push_back(m);
  }
  return g;
}

TEST(BlockRebalance, MovesBorderPosesOnlyUntilTheBoundHolds) {
  // Block 0 holds 0..39, block 1 holds 40..41 (a robot that just joined).
  const PoseGraph g = chain(42);
  std::vector<int> owner(42, 0);
  owner[40] = owner[41] = 1;
  RebalanceOptions o;
  o.slack = 0.0;
  o.min_excess = 0;
  const RebalanceResult r = rebalance_blocks(g, owner, 2, o);
  // Bound ceil(42/2) = 21: 19 poses move, the ones next to the border (39, 38, ...).
  EXPECT_EQ(r.largest_before, 40u);
  EXPECT_EQ(r.largest_after, 21u);
  EXPECT_EQ(r.moved, 19u);
  for (std::size_t k = 0; k < 42; ++k) EXPECT_EQ(owner[k], k < 21 ? 0 : 1) << k;
}

TEST(BlockRebalance, LeavesBlocksWithinSlackAlone) {
  const PoseGraph g = chain(42);
  std::vector<int> owner(42, 0);
  for (std::size_t k = 25; k < 42; ++k) owner[k] = 1;  // 25 / 17
  RebalanceOptions o;                                  // bound 1.2 * 21 + 10
  EXPECT_EQ(rebalance_blocks(g, owner, 2, o).moved, 0u);
  o.enabled = false;
  owner.assign(42, 0);
  owner[41] = 1;
  EXPECT_EQ(rebalance_blocks(g, owner, 2, o).moved, 0u);
}

TEST(BlockRebalance, RejectsANegativeSlackNamingTheField) {
  RebalanceOptions o;
  o.slack = -0.1;
  EXPECT_NE(test::validation_message(o).find("RebalanceOptions.slack"), std::string::npos);
}

TEST(OnlineRebalance, ALateRobotGetsPosesAndTheFinalAnswerEqualsTheBatchOptimum) {
  GeneratorOptions gen_options;
  gen_options.kind = TrajectoryKind::kCity;
  gen_options.num_poses = 120;
  gen_options.num_robots = 3;
  gen_options.seed = 5;
  const auto gen = generate_pose_graph(gen_options);
  ReplayOptions ro;
  ro.start_s = {0.0, 0.0, 5.0};  // robot 2 starts when robots 0 and 1 are done
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  OnlineOptions o;
  o.solver.grad_norm_tol = 1e-5;
  o.rebalance.slack = 0.1;
  o.rebalance.min_excess = 2;
  const OnlineResult res = run_online(gen.graph.d, plan.batches, o);
  // Robot 2's first poses arrive next to robot 1's block (their rendezvous measurement), so
  // robot 1's border poses move to the new, small block.
  EXPECT_GT(res.repartitions, 0);
  EXPECT_GT(res.poses_moved, 0u);
  const double f_star = solve_centralized(gen.graph).cost;
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
  ASSERT_TRUE(res.certified.has_value());
  EXPECT_TRUE(*res.certified);
}

}  // namespace
}  // namespace tessera
