// One online agent's view without DDS (runtime/online_agent_view.hpp): agents that received
// the same batches in different orders and enter what all of them hold build the same graph,
// the same blocks and the same composed estimate; a batch after a gap waits.

#include "runtime/online_agent_view.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <tessera/generate/generator.hpp>
#include <tessera/online/absorb_gate.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {
namespace {

ReplayPlan small_plan() {
  GeneratorOptions g;
  g.num_poses = 60;
  g.num_robots = 3;
  const GeneratorResult r = generate_pose_graph(g);
  return plan_replay(r.graph, r.robot_of, ReplayOptions{});
}

OnlineOptions online_options() {
  OnlineOptions o;
  o.solver.rank = 5;
  return o;
}

TEST(OnlineAgentView, AgentsThatReceivedBatchesInDifferentOrdersEnterTheSameGraphAndEstimate) {
  const ReplayPlan plan = small_plan();
  runtime::OnlineAgentView a(0, 3, online_options()), b(1, 3, online_options());
  // a receives the first two thirds in publication order, b all of it backwards.
  const std::size_t part = 2 * plan.batches.size() / 3;
  for (std::size_t k = 0; k < part; ++k) a.receive(plan.batches[k], 3, false);
  for (std::size_t k = plan.batches.size(); k-- > 0;) b.receive(plan.batches[k], 3, false);
  AbsorbGate gate;
  const Watermarks decision = gate.decide({a.held(), b.held()});
  a.enter(decision);
  b.enter(decision);
  const PoseGraph& ga = a.stream()->graph();
  const PoseGraph& gb = b.stream()->graph();
  ASSERT_GT(ga.num_poses, 0u);
  ASSERT_EQ(ga.num_poses, gb.num_poses);
  ASSERT_EQ(ga.measurements.size(), gb.measurements.size());
  for (std::size_t k = 0; k < ga.measurements.size(); ++k) {
    EXPECT_EQ(ga.measurements[k].i, gb.measurements[k].i);
    EXPECT_EQ(ga.measurements[k].j, gb.measurements[k].j);
  }
  EXPECT_EQ(a.stream()->key_of_pose(), b.stream()->key_of_pose());
  EXPECT_TRUE(a.iterate() == b.iterate());
  const LinkedProblem pa = a.problem(), pb = b.problem();
  EXPECT_EQ(pa.blocks, pb.blocks);
  // b holds more than a, so it entered only what a held too: the rest waits in its buffer.
  EXPECT_LT(ga.num_poses, 60u);
  b.enter(b.held());
  EXPECT_EQ(b.stream()->graph().num_poses, 60u);
}

TEST(OnlineAgentView, ABatchAfterAGapWaitsUntilTheMissingOneArrives) {
  const ReplayPlan plan = small_plan();
  runtime::OnlineAgentView v(0, 3, online_options());
  std::vector<StreamBatch> robot0;
  for (const auto& batch : plan.batches)
    if (batch.robot == 0) robot0.push_back(batch);
  ASSERT_GE(robot0.size(), 3u);
  v.receive(robot0[0], 3, false);
  v.receive(robot0[2], 3, false);
  EXPECT_EQ(v.held().at(0), 1u);
  v.receive(robot0[1], 3, false);
  EXPECT_EQ(v.held().at(0), 3u);
}

TEST(OnlineAgentView, TheStreamIsOverOnlyWhenEveryRobotsLastBatchEntered) {
  const ReplayPlan plan = small_plan();
  runtime::OnlineAgentView v(0, 3, online_options());
  std::map<std::uint32_t, std::size_t> last;
  for (std::size_t k = 0; k < plan.batches.size(); ++k) last[plan.batches[k].robot] = k;
  for (std::size_t k = 0; k < plan.batches.size(); ++k)
    v.receive(plan.batches[k], 3, last[plan.batches[k].robot] == k);
  Watermarks held = v.held();
  held[2] -= 1;  // robot 2's last batch not entered yet
  v.enter(held);
  EXPECT_FALSE(v.stream_over());
  v.enter(v.held());
  EXPECT_TRUE(v.stream_over());
  EXPECT_EQ(v.stream()->graph().num_poses, 60u);
}

TEST(OnlineAgentView, ABatchOfARobotOutsideTheRunIsRefused) {
  const ReplayPlan plan = small_plan();
  runtime::OnlineAgentView v(0, 2, online_options());
  const auto robot2 = std::find_if(plan.batches.begin(), plan.batches.end(),
                                   [](const StreamBatch& b) { return b.robot == 2; });
  ASSERT_NE(robot2, plan.batches.end());
  EXPECT_THROW(v.receive(*robot2, 3, false), InputError);
}

}  // namespace
}  // namespace tessera
