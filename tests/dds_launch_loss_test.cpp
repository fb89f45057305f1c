// `tessera launch --on-agent-loss continue`: an agent process SIGKILLed during the rounds no
// longer stops the run; the coordinator re-partitions its block among the survivors, which
// finish with N-1 agents, every pose and the centralized optimum. A second loss in the same
// run stops it with a message naming the agent. The default (stop) is covered by
// DdsLaunch.AgentKilledDuringTheRoundsIsNamedByEveryone (dds_solve_test.cpp).
// Domains used here: 221-222 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <thread>
#include <vector>

#include "dds_process_support.hpp"
#include "merged_estimate_checks.hpp"

namespace tessera::test::dds {
namespace {

// One launch of its own run id on a 300-pose grid3d with 5 agents; its processes are found
// (and, if an assertion fails, removed) by that run id.
struct LaunchRun {
  std::string dir, graph, run_id;
  int domain = 0;
  ~LaunchRun() { run_command("pkill -9 -f '[t]essera-.*--run-id " + run_id + " '", nullptr); }

  Process launch(const std::vector<std::string>& extra) const {
    std::vector<std::string> argv = {
        bin("tessera"),
        "launch",
        graph,
        "--agents",
        "5",
        "--domain",
        std::to_string(domain),
        "--run-id",
        run_id,
        "--init",
        "file",
        "--partition",
        "eco",
        "--on-agent-loss",
        "continue",
        "--rejoin-timeout",
        "2",  // the false-alarm window (a live peer dropped by the lease under load)
        "--replica-every",
        "5",
        "--status-interval",
        "1",
        "--out",
        dir + "/merged.g2o",
        "--json",
        dir + "/summary.json",
        "--timeout",
        "60"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return start(argv, dir + "/launch.log");
  }

  // The pid of agent k of this run, once launch has started it (0 when not found within
  // 30 s). Looked up before the round it is killed at: pgrep on a loaded host can take longer
  // than what is left of the run.
  pid_t agent_pid(int k) const {
    const auto until = Clock::now() + std::chrono::seconds(30);
    while (Clock::now() < until) {
      if (const pid_t pid = dds::agent_pid(run_id, k); pid > 0) return pid;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return 0;
  }
};

LaunchRun make_run(int domain, const std::string& name) {
  LaunchRun r;
  r.dir = temp_dir();
  r.domain = domain;
  r.run_id = name + "-" + std::to_string(getpid());
  r.graph = generate_graph(r.dir + "/graph.g2o", "--kind grid3d --poses 300 --robots 5 --seed 3");
  return r;
}

TEST(DdsLaunchLoss, KilledAgentLeavesFourAgentsThatFinishAtTheOptimumWithEveryPose) {
  LaunchRun r = make_run(221, "launchloss");
  Process launch = r.launch({"--grad-tol", "0.0005"});
  const pid_t victim = r.agent_pid(2);
  ASSERT_GT(victim, 0) << launch.output();
  ASSERT_TRUE(wait_for_round(launch, 10, 40)) << launch.output();
  ASSERT_EQ(kill(victim, SIGKILL), 0) << launch.output();
  ASSERT_TRUE(wait_all({&launch}, 60)) << launch.output();
  const std::string out = launch.output();
  EXPECT_EQ(launch.exit_code, 0) << out;
  EXPECT_NE(out.find("agent 2 ended during the run"), std::string::npos) << out;
  EXPECT_NE(out.find("re-partitioned"), std::string::npos) << out;
  EXPECT_NE(out.find("finished without agent 2"), std::string::npos) << out;

  // Every pose is in the merged estimate, and its cost is the centralized optimum's.
  const std::string summary = expect_every_pose_at_the_optimum(r.graph, r.dir);
  EXPECT_NE(summary.find("\"lost_agents\": [2]"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"survivors\": [0, 1, 3, 4]"), std::string::npos) << summary;
}

TEST(DdsLaunchLoss, SecondLossInTheSameRunStopsItNamingTheAgent) {
  LaunchRun r = make_run(222, "launchloss2");
  // A tolerance the rounds never reach, and no refinement (with `--refine auto` the rounds hand
  // over to the Newton refinement at gradient 30 and this graph's run ends in about a second,
  // before the kills): it is still in its rounds at the second kill.
  Process launch = r.launch(
      {"--grad-tol", "1e-12", "--max-rounds", "100000", "--no-certify", "--refine", "none"});
  const pid_t first = r.agent_pid(2), second = r.agent_pid(3);
  ASSERT_GT(first, 0) << launch.output();
  ASSERT_GT(second, 0) << launch.output();
  ASSERT_TRUE(wait_for_round(launch, 10, 40)) << launch.output();
  ASSERT_EQ(kill(first, SIGKILL), 0) << launch.output();
  ASSERT_TRUE(wait_for_output(launch, "re-partitioned", 30)) << launch.output();
  ASSERT_EQ(kill(second, SIGKILL), 0) << launch.output();
  ASSERT_TRUE(wait_all({&launch}, 40)) << launch.output();
  const std::string out = launch.output();
  EXPECT_EQ(launch.exit_code, 1) << out;
  EXPECT_NE(out.find("agent 3 ended during the run"), std::string::npos) << out;
  EXPECT_NE(out.find("coordinator failed"), std::string::npos) << out;
  EXPECT_NE(out.find("lost agent 3 after a re-partition: a second loss is not covered"),
            std::string::npos)
      << out;
}

// The fault benchmarks kill an agent when a given round's line appears: with
// --progress-interval 0 and replicas on (the coordinator reads every round status), every
// round of the solve has its line, in order; a bad interval is an error naming the option.
TEST(DdsLaunchLoss, ProgressIntervalZeroPrintsEveryRound) {
  const LaunchRun run = make_run(174, "every-round");
  Process launch = run.launch({"--no-certify", "--progress-interval", "0"});
  ASSERT_TRUE(wait_all({&launch}, 60)) << launch.output();
  ASSERT_EQ(launch.exit_code, 0) << launch.output();
  std::vector<long> rounds;
  std::istringstream lines(launch.output());
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("round ", 0) == 0 && line.find(" (restart)") == std::string::npos)
      rounds.push_back(std::stol(line.substr(6)));
  ASSERT_GE(rounds.size(), 5u) << launch.output();
  for (std::size_t i = 1; i < rounds.size(); ++i)
    EXPECT_EQ(rounds[i], rounds[i - 1] + 1) << "round lines skip after " << rounds[i - 1];
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " launch --progress-interval -1", &out), 2) << out;
  EXPECT_NE(out.find("--progress-interval must be in 0..3600"), std::string::npos) << out;
}

TEST(DdsLaunchLoss, LossOptionsAreCheckedNamingTheOption) {
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " launch --on-agent-loss maybe", &out), 2) << out;
  EXPECT_NE(out.find("--on-agent-loss 'maybe' is not one of stop, continue"), std::string::npos)
      << out;
  EXPECT_EQ(run_command(bin("tessera") + " launch --replicas 2", &out), 2) << out;
  EXPECT_NE(out.find("--replicas needs --on-agent-loss continue"), std::string::npos) << out;
  EXPECT_EQ(run_command(bin("tessera") + " launch --on-agent-loss continue --replicas 0", &out), 2)
      << out;
  EXPECT_NE(out.find("--replicas must be 1..8"), std::string::npos) << out;
  EXPECT_EQ(
      run_command(bin("tessera") + " launch --on-agent-loss continue --rejoin-timeout -1", &out), 2)
      << out;
  EXPECT_NE(out.find("--rejoin-timeout must be in (0, 3600]"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera::test::dds
