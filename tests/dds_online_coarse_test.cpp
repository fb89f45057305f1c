// The coarse correction of the online Newton steps over DDS (--step-coarse,
// --step-coarse-min-blocks, --step-coarse-aggregates; docs/online.md): `tessera launch --online`
// passes the flags to every agent, the agents' steps use the correction and end where the
// in-process run does, and an agent started by hand with another --step-coarse (or other smoothed
// pieces) than the lead's stops with exit code 2 naming the option (the correction adds message
// steps to every agent's Newton steps). Domains 205 and 206.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

TEST(DdsOnlineCoarse, SmoothedStepsOverDdsEndWhereTheInProcessRunEnds) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 150 --robots 3");
  // Groups of two linked blocks get the correction too: it runs as soon as two robots met.
  const std::string flags =
      " --rate 20 --speedup 2 --step-coarse smoothed --step-coarse-min-blocks 2"
      " --step-coarse-aggregates 4";
  const std::string in_process =
      solve_summary(dir, graph, "--online --robots 3 --no-progress" + flags, "in_process");
  EXPECT_EQ(json_text(in_process, "certified"), "true");
  const double f_in_process = json_number(in_process, "cost");

  const std::string json = online_launch(dir, graph, 205, flags);
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(json_text(json, "certified"), "true");
  EXPECT_NEAR(json_number(json, "cost"), f_in_process, 1e-6 * f_in_process);
  for (int a = 0; a < 3; ++a) {
    const std::string agent = online_agent_summary(dir, a);
    EXPECT_EQ(json_text(agent, "step_coarse"), "\"smoothed\"") << "agent " << a;
    EXPECT_EQ(json_number(agent, "step_coarse_min_blocks"), 2) << "agent " << a;
    EXPECT_EQ(json_text(agent, "step_coarse_aggregates"), "\"4\"") << "agent " << a;
    // Some step's Newton steps ran with the smoothed pieces' coarse space: more unknowns than
    // one rigid motion per block (6 in 3D, 18 for the 3 blocks: --step-coarse blocks' space,
    // which a smoothed run whose agents lacked the pieces would fall back to).
    double largest = 0;
    for (std::size_t at = agent.find("\"coarse_unknowns\": "); at != std::string::npos;
         at = agent.find("\"coarse_unknowns\": ", at + 1))
      largest = std::max(largest, json_number(agent, "coarse_unknowns", at));
    EXPECT_GT(largest, 18) << "agent " << a;
  }

  // Bad values are launch's own input errors, before any process starts.
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph +
                            " --agents 3 --online --step-coarse pieces 2>&1",
                        &out),
            2);
  EXPECT_TRUE(contains(out, "option --step-coarse: 'pieces'")) << out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph +
                            " --agents 3 --online --step-coarse-min-blocks 1 2>&1",
                        &out),
            2);
  EXPECT_TRUE(contains(out, "option --step-coarse-min-blocks")) << out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph +
                            " --agents 3 --online --step-coarse-aggregates 0 2>&1",
                        &out),
            2);
  EXPECT_TRUE(contains(out, "option --step-coarse-aggregates")) << out;
}

TEST(DdsOnlineCoarse, AnAgentWithAnotherStepCoarseThanTheLeadsIsRefused) {
  const std::string dir = temp_dir();
  const Process other =
      refused_beside_lead(dir, "online-coarse-differs", 206, {"--step-coarse", "smoothed"});
  EXPECT_TRUE(contains(other.output(),
                       "option --step-coarse: this agent's none differs from the "
                       "lead's (agent 0) smoothed"))
      << other.output();
}

TEST(DdsOnlineCoarse, AnAgentWithOtherSmoothedPiecesThanTheLeadsIsRefused) {
  const std::string dir = temp_dir();
  const Process other =
      refused_beside_lead(dir, "online-pieces-differ", 206,
                          {"--step-coarse", "smoothed", "--step-coarse-aggregates", "auto"},
                          {"--step-coarse", "smoothed"});
  EXPECT_TRUE(contains(other.output(),
                       "option --step-coarse-aggregates: this agent's 8 differs from the "
                       "lead's (agent 0) auto"))
      << other.output();
}

}  // namespace
}  // namespace tessera::test::dds
