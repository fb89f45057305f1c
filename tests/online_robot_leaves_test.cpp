// Robots that leave an online run, without DDS: a robot that stops publishing keeps its block
// (its poses stay and are still optimised); when an agent is lost for good the survivors agree
// on it (TakeoverAgreement), reach the same graph even when one of them was an epoch boundary
// behind, and move the lost block's poses and its robot's later poses the same way
// (OnlineAgentView::take_over). The DDS run is dds_online_loss_test.

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <tessera/generate/generator.hpp>
#include <tessera/online/absorb_gate.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/centralized_solver.hpp>

#include "runtime/online_agent_view.hpp"
#include "runtime/takeover_agreement.hpp"

namespace tessera {
namespace {

GeneratorResult small_graph(std::size_t n, std::size_t robots) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = n;
  o.num_robots = robots;
  o.seed = 3;
  return generate_pose_graph(o);
}

OnlineOptions online_options() {
  OnlineOptions o;
  o.solver.rank = 5;
  o.solver.grad_norm_tol = 1e-5;
  o.solver.max_rounds = 20000;
  return o;
}

// Stream ids of robot `robot`'s poses.
std::vector<std::size_t> poses_of(const GraphStream& s, std::uint32_t robot) {
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < s.robot_of_pose().size(); ++k)
    if (s.robot_of_pose()[k] == robot) out.push_back(k);
  return out;
}

TEST(RobotLeaves, ARobotThatStopsPublishingKeepsItsBlockAndItsPosesAreStillOptimised) {
  const auto gen = small_graph(120, 3);
  ReplayOptions ro;
  ro.rate = 10;
  ro.start_s = {0.0, 2.0, 2.0};  // robot 0 publishes 0-3.9 s, robots 1 and 2 2-5.9 s
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  double robot0_end = 0.0;
  for (const auto& b : plan.batches)
    if (b.robot == 0) robot0_end = std::max(robot0_end, b.stamp);
  Eigen::MatrixXd robot0_before;
  int steps_after = 0, steps_moving_robot0 = 0;
  const OnlineResult res = run_online(
      gen.graph.d, plan.batches, online_options(),
      [&](const OnlineEngine& engine, const OnlineUpdate& u) {
        const auto ids = poses_of(engine.stream(), 0);
        const Eigen::MatrixXd now =
            gather_pose_columns(engine.iterate(), ids, engine.stream().graph().d);
        if (u.time_s > robot0_end) {
          ++steps_after;
          // Its agent is still one of the run's, and its block still holds its poses.
          EXPECT_EQ(u.agents, 3) << "at " << u.time_s << " s";
          const auto& robots = engine.stream().robots();
          const int block0 =
              static_cast<int>(std::find(robots.begin(), robots.end(), 0u) - robots.begin());
          EXPECT_GT(std::count(engine.assignment().begin(), engine.assignment().end(), block0),
                    static_cast<long>(ids.size() / 2));
          if (u.rounds + u.newton_steps > 0 && robot0_before.cols() == now.cols() &&
              (now - robot0_before).norm() > 1e-9)
            ++steps_moving_robot0;
        }
        robot0_before = now;
      });
  EXPECT_GT(steps_after, 3);
  // The other robots' closures to its trajectory keep moving its poses after it went quiet.
  EXPECT_GT(steps_moving_robot0, 0);
  EXPECT_EQ(res.graph.num_poses, gen.graph.num_poses);
  EXPECT_EQ(res.graph.measurements.size(), gen.graph.measurements.size());
  const double f_star = solve_centralized(gen.graph).cost;
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
  ASSERT_TRUE(res.certified.has_value());
  EXPECT_TRUE(*res.certified);
}

runtime::TakeoverVote vote(std::uint32_t sender, std::set<std::uint32_t> lost, std::uint32_t epoch,
                           Watermarks entered) {
  runtime::TakeoverVote v;
  v.sender = sender;
  v.lost = std::move(lost);
  v.at_epoch = epoch;
  v.entered = std::move(entered);
  return v;
}

TEST(TakeoverAgreement, CompletesWhenEverySurvivorNamesTheSameLostSet) {
  runtime::TakeoverAgreement a({0, 1, 2, 3}, 0);
  EXPECT_FALSE(a.complete());
  // Agent 0 saw 3 go; agent 1's vote also names 2, which agent 0 had not noticed yet.
  EXPECT_TRUE(a.suspect({3, 7}));  // 7 is no member: ignored
  EXPECT_EQ(a.lost(), (std::set<std::uint32_t>{3}));
  EXPECT_FALSE(a.vote(vote(0, {3}, 10, {{0, 5}, {1, 4}})));
  EXPECT_TRUE(a.vote(vote(1, {2, 3}, 11, {{0, 6}, {1, 4}, {3, 2}})));
  EXPECT_EQ(a.lost(), (std::set<std::uint32_t>{2, 3}));
  EXPECT_EQ(a.survivors(), (std::set<std::uint32_t>{0, 1}));
  EXPECT_FALSE(a.complete());  // agent 0's vote names {3} only: it votes again
  EXPECT_FALSE(a.vote(vote(0, {2, 3}, 10, {{0, 5}, {1, 4}})));
  EXPECT_FALSE(a.vote(vote(9, {0}, 10, {})));  // a non-member's vote counts nothing
  ASSERT_TRUE(a.complete());
  EXPECT_FALSE(a.counts_me_lost());
  // The run goes on past both survivors' epochs, on the graph of the one ahead.
  EXPECT_EQ(a.next_epoch(), 12u);
  EXPECT_EQ(a.entered(), (Watermarks{{0, 6}, {1, 4}, {3, 2}}));
}

TEST(TakeoverAgreement, AnAgentCountedLostKnowsIt) {
  runtime::TakeoverAgreement a({0, 1, 2}, 2);
  a.vote(vote(0, {2}, 4, {}));
  EXPECT_TRUE(a.counts_me_lost());
}

TEST(OnlineAgentView, SurvivorsAnEpochApartReachTheSameGraphAndMoveTheLostBlockAlike) {
  const auto gen = small_graph(90, 3);
  ReplayOptions ro;
  ro.rate = 10;
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  // The take-over's own moves: blocks refined for the cut would also move survivors' poses.
  OnlineOptions o = online_options();
  o.rebalance.cut_fraction = 1.0;
  runtime::OnlineAgentView ahead(0, 3, o), behind(1, 3, o);
  // Both hold the first half; `ahead` passed one more boundary than `behind`.
  const std::size_t half = plan.batches.size() / 2, third = plan.batches.size() / 3;
  for (std::size_t k = 0; k < half; ++k) {
    ahead.receive(plan.batches[k], 3, false);
    behind.receive(plan.batches[k], 3, false);
  }
  Watermarks early;
  for (std::size_t k = 0; k < third; ++k)
    early[plan.batches[k].robot] = plan.batches[k].sequence + 1;
  ahead.enter(early);
  behind.enter(early);
  ahead.enter(ahead.held());
  ASSERT_GT(ahead.stream()->graph().num_poses, behind.stream()->graph().num_poses);
  runtime::TakeoverAgreement agreement({0, 1, 2}, 1);
  agreement.suspect({2});
  agreement.vote(vote(0, {2}, 8, ahead.entered()));
  agreement.vote(vote(1, {2}, 7, behind.entered()));
  ASSERT_TRUE(agreement.complete());
  behind.enter(agreement.entered());
  EXPECT_EQ(behind.stream()->key_of_pose(), ahead.stream()->key_of_pose());
  EXPECT_EQ(behind.owner(), ahead.owner());

  const auto& robots = ahead.stream()->robots();
  const int lost_block =
      static_cast<int>(std::find(robots.begin(), robots.end(), 2u) - robots.begin());
  const auto lost_poses = std::count(ahead.owner().begin(), ahead.owner().end(), lost_block);
  ASSERT_GT(lost_poses, 0);
  const std::vector<int> before = ahead.owner();
  const runtime::TakeoverMoves moved_a = ahead.take_over(agreement.lost());
  const runtime::TakeoverMoves moved_b = behind.take_over(agreement.lost());
  EXPECT_EQ(ahead.owner(), behind.owner());
  // Only the lost poses moved, and none is left in the lost block.
  EXPECT_EQ(moved_a.moved, static_cast<std::size_t>(lost_poses));
  EXPECT_EQ(moved_b.moved, moved_a.moved);
  EXPECT_EQ(std::count(ahead.owner().begin(), ahead.owner().end(), lost_block), 0);
  for (std::size_t k = 0; k < before.size(); ++k)
    if (before[k] != lost_block) {
      EXPECT_EQ(ahead.owner()[k], before[k]) << "pose " << k;
    }

  // The lost robot keeps publishing: its later poses join one survivor block (its adopter),
  // and the blocks are not reshuffled between the survivors.
  for (std::size_t k = half; k < plan.batches.size(); ++k) {
    ahead.receive(plan.batches[k], 3, false);
    behind.receive(plan.batches[k], 3, false);
  }
  const std::size_t known = ahead.owner().size();
  const runtime::EnteredData in_a = ahead.enter(ahead.held());
  behind.enter(behind.held());
  EXPECT_EQ(ahead.owner(), behind.owner());
  EXPECT_EQ(ahead.stream()->graph().num_poses, gen.graph.num_poses);
  std::set<int> adopters;
  for (std::size_t k = known; k < ahead.owner().size(); ++k) {
    EXPECT_NE(ahead.owner()[k], lost_block) << "pose " << k;
    if (ahead.stream()->robot_of_pose()[k] == 2) adopters.insert(ahead.owner()[k]);
  }
  EXPECT_EQ(adopters.size(), 1u);
  EXPECT_EQ(in_a.moved, 0u);
}

}  // namespace
}  // namespace tessera
