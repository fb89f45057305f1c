// Online runs over DDS (tessera-agent --online, tessera launch --online): the agents solve
// the graph while the replay streams it in, agree on the epoch each batch enters, idle
// without traffic, take in an agent started late, and end at the batch optimum, certified.
// Domains used here: 57-59 (each test its own).
// A member that goes silent stops the run (the survivors name it) unless the agents run with
// --on-agent-loss continue (dds_online_loss_test).

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <thread>
#include <tuple>

#include "dds_process_support.hpp"
#include "transport/online_channel.hpp"

namespace tessera::test::dds {
namespace {

// The batch optimum f* of `graph` (centralized solver, certified).
double batch_optimum(const std::string& dir, const std::string& graph) {
  const std::string json = solve_summary(dir, graph, "", "batch");
  EXPECT_EQ(json_text(json, "certified"), "true");
  return json_number(json, "cost");
}

// (epoch, total poses, total measurements) of every update an agent wrote.
std::map<long, std::pair<long, long>> updates_of(const std::string& json) {
  std::map<long, std::pair<long, long>> out;
  const std::size_t begin = json.find("\"updates\"");
  if (begin == std::string::npos) return out;
  const std::string updates = json.substr(begin, json.find("\n  ]", begin) - begin);
  for (std::size_t at = updates.find("{\"epoch\": "); at != std::string::npos;
       at = updates.find("{\"epoch\": ", at + 1))
    out[std::stol(json_text(updates, "epoch", at))] = {
        std::stol(json_text(updates, "total_poses", at)),
        std::stol(json_text(updates, "total_measurements", at))};
  return out;
}

TEST(DdsOnline, TheOnlineLaunchEndsAtTheBatchOptimumAndEveryAgentSolvesTheSameGraphs) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 150 --robots 3");
  const double f_star = batch_optimum(dir, graph);
  const std::string json = online_launch(
      dir, graph, 57,
      "--rate 20 --speedup 2 --publish-every 0.2 --certify-every 0.5 --tum-dir " + dir + "/tum");
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(json_text(json, "certified"), "true");
  EXPECT_NEAR(json_number(json, "cost"), f_star, 1e-6 * f_star);
  const PoseGraph batch = read_g2o(graph);
  EXPECT_EQ(json_number(json, "total_poses"), static_cast<double>(batch.num_poses));
  EXPECT_EQ(json_number(json, "total_measurements"),
            static_cast<double>(batch.measurements.size()));
  EXPECT_GE(json_number(json, "solves"), 2);
  // Per-robot TUM snapshots: the last one holds each robot's 50 poses.
  for (int r = 0; r < 3; ++r) {
    const std::string tum = read_text_file(dir + "/tum/robot" + std::to_string(r) + ".tum");
    EXPECT_EQ(std::count(tum.begin(), tum.end(), '\n'), 50) << "robot " << r;
  }
  EXPECT_GE(json_number(json, "publications"), 1);
  // A new measurement (inter-robot closures included) enters every agent at the same epoch:
  // whenever two agents solved at an epoch, they solved the same graph.
  const auto lead = updates_of(online_agent_summary(dir, 0));
  ASSERT_FALSE(lead.empty());
  for (int a = 1; a < 3; ++a) {
    const auto other = updates_of(online_agent_summary(dir, a));
    int common = 0;
    for (const auto& [epoch, sizes] : other) {
      auto it = lead.find(epoch);
      if (it == lead.end()) continue;
      ++common;
      EXPECT_EQ(it->second, sizes) << "agent " << a << " epoch " << epoch;
    }
    EXPECT_GE(common, 2) << "agent " << a;
  }
}

TEST(DdsOnline, TheOnlineLaunchForwardsTheStepSolverToEveryAgent) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 150 --robots 3");
  const double f_star = batch_optimum(dir, graph);
  const std::string json =
      online_launch(dir, graph, 136, "--rate 20 --speedup 2 --step-solver rounds");
  ASSERT_FALSE(::testing::Test::HasFailure());
  EXPECT_EQ(json_text(json, "certified"), "true");
  EXPECT_NEAR(json_number(json, "cost"), f_star, 1e-6 * f_star);
  for (int a = 0; a < 3; ++a) {
    const std::string agent = online_agent_summary(dir, a);
    EXPECT_EQ(json_text(agent, "step_solver"), "\"rounds\"") << "agent " << a;
    // Rounds only: the steps that solved did it by block-coordinate rounds.
    EXPECT_GT(json_number(agent, "rounds"), 0) << "agent " << a;
  }
  // A bad value is an input error of launch itself, before any process starts.
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph +
                            " --agents 3 --online --step-solver gauss 2>&1",
                        &out),
            2);
  EXPECT_NE(out.find("--step-solver"), std::string::npos) << out;
}

TEST(DdsOnline, ALateAgentJoinsIdleAgentsSendNothingAndTheAnswerIsTheBatchOptimum) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  const std::string run = "online-late";
  generate_graph(graph, "--kind grid3d --poses 150 --robots 3");
  const double f_star = batch_optimum(dir, graph);
  // Robots 0 and 1 play their 50 poses each in about 0.6 s; robot 2 starts 6 s later. Its
  // agent starts at 4 s: until then the run has two agents, which have nothing new from
  // about 1 s on (nothing may be sent between 2.5 and 3.5 s).
  // Reads the agents' topics (never writes) and notes when each sample arrived.
  transport::OnlineChannel snoop(58, run, 99, 3);
  std::mutex mutex;
  std::vector<double> arrivals;
  std::atomic<bool> stop{false};
  const auto t0 = Clock::now();
  auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  std::thread reader([&] {
    while (!stop) {
      snoop.wait(0.01);
      const std::size_t n = snoop.take_reports().size() + snoop.take_messages().size();
      std::lock_guard<std::mutex> lock(mutex);
      arrivals.insert(arrivals.end(), n, seconds());
    }
  });
  Process replay =
      start({bin("tessera"), "replay", graph, "--robots", "3", "--run-id", run, "--domain", "58",
             "--rate", "40", "--speedup", "2", "--start", "0,0,12", "--linger", "1"},
            dir + "/replay.log");
  auto agent = [&](int id) {
    return start(online_agent_args(
                     3, id, run, 58,
                     {"--timeout", "60", "--json", dir + "/agent" + std::to_string(id) + ".json"}),
                 dir + "/agent" + std::to_string(id) + ".log");
  };
  Process a0 = agent(0), a1 = agent(1);
  while (seconds() < 4.0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  Process a2 = agent(2);
  const bool ended = wait_all({&replay, &a0, &a1, &a2}, 180);
  stop = true;
  reader.join();
  ASSERT_TRUE(ended) << "a process hung";
  std::size_t idle_samples = 0, samples_before = 0;
  for (double t : arrivals) {
    idle_samples += t >= 2.5 && t < 3.5 ? 1 : 0;
    samples_before += t < 2.5 ? 1 : 0;
  }
  EXPECT_GT(samples_before, 0u);  // the snoop did hear the run
  EXPECT_EQ(idle_samples, 0u) << "the idle agents sent something between 2.5 s and 3.5 s";
  for (Process* p : {&replay, &a0, &a1, &a2}) EXPECT_EQ(p->exit_code, 0) << p->output();
  const std::string json = read_text_file(dir + "/agent0.json");
  EXPECT_EQ(json_text(json, "certified"), "true");
  EXPECT_NEAR(json_number(json, "cost"), f_star, 1e-6 * f_star);
  EXPECT_EQ(json_number(json, "total_poses"), 150.0);
  // The idle stretch shows in the summaries: waits without a solve.
  EXPECT_GE(json_number(json, "idle_waits"), 1);
  // The late agent solved with the others once its robot's data entered (in the final solve
  // at least: when its robot's whole trajectory entered at once, the stream was over).
  const std::string late = read_text_file(dir + "/agent2.json");
  EXPECT_GT(json_number(late, "solves") + json_number(late, "final_rounds"), 0);
  EXPECT_EQ(json_text(late, "certified"), "true");
}

TEST(DdsOnline, WhenAMemberGoesSilentTheOthersStopNamingIt) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  const std::string run = "online-silent";
  generate_graph(graph, "--kind grid3d --poses 300 --robots 3");
  // 100 poses per robot at 20 per second: the stream lasts 5 s; agent 2 ends after 2 s.
  Process replay = start({bin("tessera"), "replay", graph, "--robots", "3", "--run-id", run,
                          "--domain", "59", "--rate", "20", "--linger", "1"},
                         dir + "/replay.log");
  std::vector<Process> agents;
  for (int id = 0; id < 3; ++id)
    agents.push_back(start(online_agent_args(3, id, run, 59, {"--timeout", "3"}),
                           dir + "/agent" + std::to_string(id) + ".log"));
  std::this_thread::sleep_for(std::chrono::seconds(2));
  kill(agents[2].pid, SIGTERM);
  ASSERT_TRUE(wait_all({&replay, &agents[0], &agents[1], &agents[2]}, 60)) << "a process hung";
  for (int id = 0; id < 2; ++id) {
    EXPECT_EQ(agents[static_cast<std::size_t>(id)].exit_code, 1);
    EXPECT_TRUE(contains(agents[static_cast<std::size_t>(id)].output(), "agent 2"))
        << agents[static_cast<std::size_t>(id)].output();
  }
}

}  // namespace
}  // namespace tessera::test::dds
