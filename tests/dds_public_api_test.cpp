// The public entry points of DDS runs (<tessera/dds/...>, Tessera::dds): run_coordinator()
// hosted in this test process finishes a run with two tessera-agent processes, run_agent()
// hosted here finishes one with a tessera-coordinator process and another agent, each giving
// the in-process engine's rounds; their options name a bad field.
// Domains used here: 10-11.

#include <gtest/gtest.h>

#include <string>
#include <tessera/dds/agent.hpp>
#include <tessera/dds/coordinator.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

// A small graph and the rounds `tessera solve` needs for it with 2 agents (partition eco).
struct SmallRun {
  std::string dir = temp_dir();
  std::string graph;
  double rounds = 0;

  SmallRun() {
    graph = generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 120 --robots 2 --seed 4");
    std::string out;
    EXPECT_EQ(run_command(bin("tessera") + " solve " + graph +
                              " --agents 2 --algorithm irbcd --partition eco --seed 1 --json " +
                              dir + "/ip.json 2>&1",
                          &out),
              0)
        << out;
    rounds = json_field(slurp(dir + "/ip.json"), "rounds");
    EXPECT_GT(rounds, 1) << "the graph should need a few rounds";
  }
};

TEST(DdsPublicApi, HostedCoordinatorFinishesTheRunWithTheInProcessRounds) {
  const SmallRun run;
  const std::string id = "api-coordinator-" + std::to_string(getpid());
  std::vector<Process> agents;
  for (int k = 0; k < 2; ++k)
    agents.push_back(start(agent_args(run.graph, 2, k, id, 10),
                           run.dir + "/agent" + std::to_string(k) + ".log"));
  tessera::dds::CoordinatorOptions o;
  o.agents = 2;
  o.session.run_id = id;
  o.session.domain = 10;
  o.partition = "eco";
  o.extra_args = {"--graph", run.graph, "--init", "chordal"};
  const tessera::dds::RunSummary summary = tessera::dds::run_coordinator(o);
  std::vector<Process*> all;
  for (auto& a : agents) all.push_back(&a);
  ASSERT_TRUE(wait_all(all, 60));
  EXPECT_EQ(summary.exit_code, 0) << summary.full_report();
  for (auto& a : agents) EXPECT_EQ(a.exit_code, 0) << a.output();
  EXPECT_EQ(json_field(summary.summary_json, "rounds"), run.rounds) << summary.summary_json;
  EXPECT_NE(summary.full_report().find("run " + id + ": done"), std::string::npos)
      << summary.full_report();
}

TEST(DdsPublicApi, HostedAgentFinishesTheRunWithTheInProcessRounds) {
  const SmallRun run;
  const std::string id = "api-agent-" + std::to_string(getpid());
  Process coordinator = start(coordinator_args(2, id, 11,
                                               {"--partition", "eco", "--graph", run.graph,
                                                "--summary", run.dir + "/summary.json"}),
                              run.dir + "/coordinator.log");
  Process other = start(agent_args(run.graph, 2, 1, id, 11), run.dir + "/agent1.log");
  tessera::dds::AgentOptions o;
  o.graph = run.graph;
  o.robots = 2;
  o.id = 0;
  o.session.run_id = id;
  o.session.domain = 11;
  o.output = run.dir + "/agent0.g2o";
  const tessera::dds::AgentResult result = tessera::dds::run_agent(o);
  ASSERT_TRUE(wait_all({&coordinator, &other}, 60));
  EXPECT_EQ(result.exit_code, 0) << result.full_report();
  EXPECT_EQ(coordinator.exit_code, 0) << coordinator.output();
  EXPECT_EQ(other.exit_code, 0) << other.output();
  EXPECT_EQ(json_field(slurp(run.dir + "/summary.json"), "rounds"), run.rounds);
  EXPECT_NE(slurp(o.output).find("VERTEX"), std::string::npos);
  EXPECT_NE(result.full_report().find("agent 0 of run " + id + ": done"), std::string::npos)
      << result.full_report();
}

TEST(DdsPublicApi, OptionsNameTheBadField) {
  tessera::dds::AgentOptions agent;
  agent.graph = "g.g2o";
  agent.robots = 2;
  agent.id = 2;  // 0..1
  EXPECT_TRUE(test::validation_names(agent, "--id"));
  tessera::dds::CoordinatorOptions coordinator;
  coordinator.agents = 2;
  coordinator.session.lease_s = 0.01;  // 0.2..60
  EXPECT_TRUE(test::validation_names(coordinator, "lease"));
}

}  // namespace
}  // namespace tessera::test::dds
