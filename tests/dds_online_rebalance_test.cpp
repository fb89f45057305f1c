// The re-partition options of an online run over DDS (docs/online.md, "The partition follows
// the graph"): every agent moves the blocks itself, so `tessera launch --online` passes its
// flags to every agent, the agents make the moves that the in-process view makes with the same
// options and entered batches, and an agent started by hand with other options than the lead's
// stops with exit code 2 naming the option. Domain 178.

#include <gtest/gtest.h>

#include <string>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <vector>

#include "dds_process_support.hpp"
#include "runtime/online_agent_view.hpp"
#include "runtime/replay_input.hpp"

namespace tessera::test::dds {
namespace {

// The numbers of a JSON array field ("key": [a, b, ...]) at or after `from`.
std::vector<std::size_t> json_sizes(const std::string& json, const std::string& key,
                                    std::size_t from) {
  std::vector<std::size_t> out;
  const std::size_t at = json.find("\"" + key + "\": [", from);
  if (at == std::string::npos) return out;
  std::size_t k = json.find('[', at) + 1;
  const std::size_t end = json.find(']', k);
  while (k < end) {
    std::size_t used = 0;
    out.push_back(std::stoul(json.substr(k, end - k), &used));
    k = json.find_first_not_of(", ", k + used);
  }
  return out;
}

struct Update {
  std::vector<std::size_t> entered;  // batches per robot
  long moved = 0, largest = 0, smallest = 0, cut = 0;
};

std::vector<Update> updates_of(const std::string& json) {
  std::vector<Update> out;
  const std::size_t begin = json.find("\"updates\"");
  if (begin == std::string::npos) return out;
  for (std::size_t at = json.find("{\"epoch\": ", begin); at != std::string::npos;
       at = json.find("{\"epoch\": ", at + 1)) {
    Update u;
    u.entered = json_sizes(json, "entered", at);
    u.moved = std::stol(json_text(json, "moved", at));
    u.largest = std::stol(json_text(json, "largest_block", at));
    u.smallest = std::stol(json_text(json, "smallest_block", at));
    u.cut = std::stol(json_text(json, "cut", at));
    out.push_back(u);
  }
  return out;
}

TEST(DdsOnlineRebalance, TheLaunchsOptionsReachEveryAgentWhichMovesAsInProcessAndOthersAreRefused) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/city.g2o";
  // One city trajectory split into 3 robots: their blocks cross, so the refinement moves poses.
  generate_graph(graph, "--kind city --poses 300 --robots 3 --seed 3");
  const std::vector<std::string> flags = {"--cut-fraction", "0.05", "--block-slack", "0.3",
                                          "--cut-patience", "32"};
  std::string flag_text;
  for (const auto& f : flags) flag_text += " " + f;

  // A bad value is launch's own input error, before any process starts.
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph +
                            " --agents 3 --online --cut-fraction 1.5 2>&1",
                        &out),
            2);
  EXPECT_NE(out.find("--cut-fraction"), std::string::npos) << out;

  // The same graph and flags in one process: the answer the DDS run must reach.
  const std::string in_process = solve_summary(
      dir, graph, "--online --robots 3 --rate 20 --speedup 2 --no-progress" + flag_text,
      "in_process");
  EXPECT_EQ(json_text(in_process, "certified"), "true");
  const double f_online = json_number(in_process, "cost");

  const std::string json = online_launch(dir, graph, 178, "--rate 20 --speedup 2" + flag_text);
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(json_text(json, "certified"), "true");
  EXPECT_NEAR(json_number(json, "cost"), f_online, 1e-6 * f_online);

  // Every agent used the launch's options.
  std::vector<std::string> agent(3);
  for (int a = 0; a < 3; ++a) {
    agent[static_cast<std::size_t>(a)] = online_agent_summary(dir, a);
    const std::string& j = agent[static_cast<std::size_t>(a)];
    EXPECT_EQ(json_number(j, "cut_fraction"), 0.05) << "agent " << a;
    EXPECT_EQ(json_number(j, "slack"), 0.3) << "agent " << a;
    EXPECT_EQ(json_number(j, "pass_patience"), 32) << "agent " << a;
  }

  // The lead's moves, epoch by epoch, are those of the in-process view given the same options
  // and the batches that entered at each epoch; so are every agent's final blocks.
  OnlineOptions options;
  options.rebalance.cut_fraction = 0.05;
  options.rebalance.slack = 0.3;
  options.rebalance.pass_patience = 32;
  const runtime::ReplayInput input = runtime::replay_input_from_file(graph, 3);
  ReplayOptions replay;
  replay.rate = 20;
  replay.speedup = 2;
  const ReplayPlan plan = plan_replay(input.graph, input.robot_of_pose, replay);
  runtime::OnlineAgentView view(0, 3, options);
  for (const StreamBatch& b : plan.batches) view.receive(b, input.graph.d, false);
  const std::vector<Update> updates = updates_of(agent[0]);
  ASSERT_GE(updates.size(), 3u);
  long moved = 0;
  for (std::size_t k = 0; k < updates.size(); ++k) {
    const Update& u = updates[k];
    ASSERT_EQ(u.entered.size(), 3u) << "update " << k;
    Watermarks decision;
    for (std::uint32_t r = 0; r < 3; ++r) decision[r] = u.entered[r];
    const runtime::EnteredData in = view.enter(decision);
    EXPECT_EQ(static_cast<long>(in.moved), u.moved) << "update " << k;
    EXPECT_EQ(static_cast<long>(in.largest_block), u.largest) << "update " << k;
    EXPECT_EQ(static_cast<long>(in.smallest_block), u.smallest) << "update " << k;
    EXPECT_EQ(static_cast<long>(in.cut), u.cut) << "update " << k;
    moved += u.moved;
  }
  view.enter(view.held());  // the final epoch: everything
  std::vector<std::size_t> blocks(3, 0);
  for (int b : view.owner()) ++blocks[view.stream()->robots()[static_cast<std::size_t>(b)]];
  for (int a = 0; a < 3; ++a) {
    const std::string& j = agent[static_cast<std::size_t>(a)];
    EXPECT_EQ(json_sizes(j, "final_blocks", 0), blocks) << "agent " << a;
    EXPECT_EQ(json_number(j, "final_cut"),
              static_cast<double>(cut_measurements(view.stream()->graph(), view.owner())))
        << "agent " << a;
  }
  EXPECT_GT(moved + static_cast<long>(cut_measurements(view.stream()->graph(), view.owner())), 0);

  // An agent started by hand with another cut fraction than the lead's stops, naming it (the
  // lead does not admit it, when its hello arrived before it stopped).
  const Process other =
      refused_beside_lead(dir, "online-rebalance-differs", 178, {"--cut-fraction", "0.05"});
  EXPECT_TRUE(contains(other.output(), "option --cut-fraction")) << other.output();
  EXPECT_TRUE(contains(other.output(), "0.02")) << other.output();
  EXPECT_TRUE(contains(other.output(), "0.05")) << other.output();
}

}  // namespace
}  // namespace tessera::test::dds
