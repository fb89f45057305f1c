// Real distributed solves over DDS: the agents run core's round protocol as processes and must
// give the same iterates as the in-process engine; `tessera launch` end to end.
// Domains used here: 161-170, 175, 176, 129, 56, 131 and 112-113 (each test its own, so ctest -j is
// safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <vector>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

std::string generate(const std::string& dir, int poses, int robots, int seed) {
  return generate_graph(dir + "/graph.g2o", "--kind grid3d --poses " + std::to_string(poses) +
                                                " --robots " + std::to_string(robots) + " --seed " +
                                                std::to_string(seed));
}

// Pose k's position in pose 0's frame: free of the rotation frame the rounding picks.
Eigen::VectorXd in_frame_of_pose_0(const std::vector<Pose>& p, std::size_t k) {
  return p[0].R.transpose() * (p[k].t - p[0].t);
}

FinishedRun run_dds(const std::string& dir, const std::string& graph, int agents, int domain,
                    const std::vector<std::string>& solver_args) {
  const std::string run = "solve-" + std::to_string(getpid()) + "-" + std::to_string(domain);
  std::vector<std::string> cargs = {
      "--timeout", "20", "--run-timeout", "60", "--output", dir + "/merged.g2o", "--progress"};
  cargs.insert(cargs.end(), solver_args.begin(), solver_args.end());
  return run_and_read(dir, graph, agents, run, domain, cargs, 60);
}

void expect_same_as_in_process(const std::string& algorithm, int domain, bool status_relay = true,
                               bool coarse = false, bool smoothed = false, int agents = 3) {
  const std::string dir = temp_dir();
  const std::string graph = generate(dir, 240, 3, 5);
  std::vector<std::string> coordinator_args = {"--partition", "eco", "--algorithm", algorithm,
                                               "--seed",      "7",   "--init",      "file"};
  if (!status_relay) coordinator_args.push_back("--no-status-relay");
  if (coarse) coordinator_args.insert(coordinator_args.end(), {"--coarse-every", "1"});
  if (smoothed)
    coordinator_args.insert(coordinator_args.end(),
                            {"--coarse-space", "smoothed", "--coarse-aggregates", "2"});
  const FinishedRun dds = run_dds(dir, graph, agents, domain, coordinator_args);
  const PoseGraph g = read_g2o(graph);
  ASSERT_EQ(dds.assignment.size(), g.num_poses);

  DistributedOptions opt;
  opt.algorithm = parse_algorithm(algorithm);
  opt.seed = 7;
  opt.coarse.enabled = coarse;
  if (smoothed) {
    opt.coarse.space = CoarseSpaceKind::kSmoothed;
    opt.coarse.aggregates = 2;
  }
  const DistributedResult ref = solve_distributed(g, dds.assignment, opt, g.initial);
  ASSERT_GT(ref.rounds, 1) << "the graph should need a few rounds";

  EXPECT_EQ(json_field(dds.summary, "rounds"), ref.rounds) << dds.summary;
  EXPECT_EQ(json_field(dds.summary, "restarts"), ref.restarts) << dds.summary;
  const double cost = json_field(dds.summary, "cost");
  EXPECT_NEAR(cost, ref.cost, 1e-9 * ref.cost) << dds.summary;
  EXPECT_NEAR(json_field(dds.summary, "grad_norm"), ref.grad_norm, 1e-9 * ref.grad_norm);

  // The merged poses have the same cost as the in-process engine's rounded poses.
  // (The merged file holds VERTEX lines only; add the input's edges so the reader takes it.)
  std::string text = slurp(dir + "/merged.g2o");
  std::ifstream in(graph);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("EDGE", 0) == 0) text += line + "\n";
  PoseGraph merged_graph = read_g2o_text(text, "merged").graph;
  ASSERT_EQ(merged_graph.initial.size(), g.num_poses);
  double f = 0.0;
  for (const auto& m : g.measurements) {
    const Pose& a = merged_graph.initial[m.i];
    const Pose& b = merged_graph.initial[m.j];
    f += m.kappa * (b.R - a.R * m.R).squaredNorm() + m.tau * (b.t - a.t - a.R * m.t).squaredNorm();
  }
  EXPECT_NEAR(f, ref.cost, 1e-8 * ref.cost);  // g2o text keeps ~17 digits per value

  // The distributed rounding's translations are the direct solve's (core's round_solution) up to
  // the translation CG's stop: it ends once the cost it could still remove is below 1e-10 of
  // f(X) (runtime/distributed_rounding.hpp), here ~1e-8 m.
  ASSERT_EQ(ref.poses.size(), g.num_poses);
  double worst = 0.0;
  for (std::size_t k = 0; k < g.num_poses; ++k)
    worst = std::max(
        worst,
        (in_frame_of_pose_0(merged_graph.initial, k) - in_frame_of_pose_0(ref.poses, k)).norm());
  EXPECT_LT(worst, 1e-7);
}

TEST(DdsSolve, IrbcdOverDdsGivesTheInProcessIterates) {
  expect_same_as_in_process("irbcd", 161);
}

TEST(DdsSolve, RbcdPlusPlusOverDdsGivesTheInProcessIterates) {
  expect_same_as_in_process("rbcd++", 162);
}

// Round statuses all to all (--no-status-relay) instead of through the relay agent (the
// default, transport/status_relay.hpp): the same statuses reach every agent, so the same
// iterates (restarts included) either way.
TEST(DdsSolve, StatusesAllToAllGiveTheInProcessIterates) {
  expect_same_as_in_process("irbcd", 167, false);
  expect_same_as_in_process("rbcd++", 168, false);
}

// Two-level rounds: the coarse terms go to agent 0 (riding in the status to the relay, or on
// their own), which solves and sends each agent its motions: the same iterates as in process.
TEST(DdsSolve, CoarseCorrectionOverDdsGivesTheInProcessIterates) {
  expect_same_as_in_process("irbcd", 129, true, true);
  expect_same_as_in_process("irbcd", 56, false, true);
}

// The smoothed coarse space: every agent builds it from the structure it holds (solver and
// agents agree on who needs which motions), so the DDS agents give the in-process iterates.
TEST(DdsSolve, SmoothedCoarseCorrectionOverDdsGivesTheInProcessIterates) {
  expect_same_as_in_process("irbcd", 131, true, true, true);
}

// The gathered coarse exchange with more agents: the terms go to agent 0 (riding in the status
// to the relay, or on their own), agent 0 solves and sends each agent its motions addressed, and
// the DDS agents give the in-process iterates.
TEST(DdsSolve, GatheredCoarseExchangeWithSixAgentsGivesTheInProcessIterates) {
  expect_same_as_in_process("irbcd", 112, true, true, true, 6);
  expect_same_as_in_process("irbcd", 113, false, true, true, 6);
}

// Kills whatever processes of run `run_id` a test leaves running when an assertion fails (a
// leftover in the same domain would otherwise be what the next run's pgrep finds).
struct RunCleanup {
  std::string run_id;
  ~RunCleanup() { run_command("pkill -9 -f '[t]essera-.*--run-id " + run_id + "'", nullptr); }
};

TEST(DdsLaunch, EndToEndOnAGeneratedGraphPrintsTheSummary) {
  const std::string dir = temp_dir();
  std::string out;
  const int rc = run_command(bin("tessera") + " launch --agents 3 --poses 150 --domain 163 " +
                                 "--partition eco --timeout 60 --json " + dir + "/s.json --out " +
                                 dir + "/merged.g2o 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_GE(last_progress_round(out), 1) << out;  // progress streamed
  EXPECT_NE(out.find("summary:"), std::string::npos) << out;
  const std::string json = slurp(dir + "/s.json");
  for (const char* field :
       {"algorithm", "graph", "poses", "edges", "d", "rank", "rounds", "iterations", "grad_norm",
        "cost", "certified", "wall_s", "agents", "partition", "restarts", "bytes_exchanged",
        "partition_ms", "bytes_sent", "discovery_ms"})
    EXPECT_NE(json.find("\"" + std::string(field) + "\":"), std::string::npos) << field << json;
  EXPECT_EQ(json_field(json, "poses"), 150);
  EXPECT_EQ(json_text(json, "rel_gap_to_reference"), "null") << json;  // no --reference-cost
  EXPECT_LE(json_field(json, "grad_norm"), 0.01);
  EXPECT_GT(json_field(json, "cost"), 0);
  std::ifstream merged(dir + "/merged.g2o");
  int vertices = 0;
  for (std::string line; std::getline(merged, line);) vertices += line.rfind("VERTEX", 0) == 0;
  EXPECT_EQ(vertices, 150);
}

// Given the optimal cost (--reference-cost), the summary reports the final cost's relative gap to
// it; a certified run of a small graph ends at that optimum.
TEST(DdsLaunch, ReportsTheRelativeGapToAGivenOptimalCost) {
  const std::string dir = temp_dir();
  const std::string graph = generate(dir, 120, 2, 1);
  const double fstar = solve_centralized(read_g2o(graph)).cost;
  std::ostringstream f;
  f.precision(17);
  f << fstar;
  std::string out;
  const int rc = run_command(bin("tessera") + " launch " + graph + " --agents 2 --domain 176 " +
                                 "--partition fast --certify --timeout 60 --reference-cost " +
                                 f.str() + " --json " + dir + "/s.json 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  const std::string json = slurp(dir + "/s.json");
  const double cost = json_field(json, "cost"), gap = json_field(json, "rel_gap_to_reference");
  EXPECT_EQ(json_field(json, "reference_cost"), fstar) << json;
  EXPECT_NEAR(gap, (cost - fstar) / fstar, 1e-15) << json;
  EXPECT_LT(std::abs(gap), 1e-6) << json;
  std::string bad;
  EXPECT_EQ(run_command(
                bin("tessera") + " launch " + graph + " --agents 2 --reference-cost -1 2>&1", &bad),
            2);
  EXPECT_NE(bad.find("--reference-cost"), std::string::npos) << bad;
}

// The summary reports each agent's peak resident set, the coordinator's and their sum, and the
// set-up's steps are progress lines before the first round.
TEST(DdsLaunch, ReportsPeakMemoryPerAgentAndTheSetUpSteps) {
  const std::string dir = temp_dir();
  std::string out;
  const int rc = run_command(bin("tessera") + " launch --agents 2 --poses 120 --domain 61 " +
                                 "--partition fast --timeout 60 --json " + dir + "/s.json 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  for (const char* step : {"agents announced: 120 poses", "partition (fast): cut",
                           "assignment sent, all agents ready"})
    EXPECT_NE(out.find(step), std::string::npos) << step << "\n" << out;
  // Before the rounds' progress lines.
  EXPECT_LT(out.find("set-up "), out.find("\nround ")) << out;
  const std::string json = slurp(dir + "/s.json");
  const std::size_t key = json.find("\"peak_rss_mb_per_agent\":");
  ASSERT_NE(key, std::string::npos) << json;
  const std::size_t open = json.find('[', key), close = json.find(']', key);
  ASSERT_LT(open, close) << json;
  std::vector<double> per_agent;
  std::istringstream list(json.substr(open + 1, close - open - 1));
  for (std::string v; std::getline(list, v, ',');) per_agent.push_back(std::stod(v));
  ASSERT_EQ(per_agent.size(), 2u) << json;
  const double agent_max = json_field(json, "peak_rss_mb_agent_max");
  const double coordinator = json_field(json, "peak_rss_mb_coordinator");
  for (double mb : per_agent) {
    EXPECT_GT(mb, 1.0) << json;  // a live process with Fast DDS loaded: megabytes at least
    EXPECT_LE(mb, agent_max) << json;
  }
  EXPECT_EQ(agent_max, std::max(per_agent[0], per_agent[1])) << json;
  EXPECT_GT(coordinator, 1.0) << json;
  EXPECT_NEAR(json_field(json, "peak_rss_mb_run"), per_agent[0] + per_agent[1] + coordinator,
              1e-6 * json_field(json, "peak_rss_mb_run"))
      << json;
}

// --heap-pages 2m reaches the run's processes: the coordinator, forked after launch re-ran itself,
// reports the page size from its own GLIBC_TUNABLES (launch/heap_pages.hpp).
TEST(DdsLaunch, TheRunsProcessesInheritTheHeapPagesLaunchChose) {
  std::ifstream thp("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode;
  std::getline(thp, mode);
  if (mode.empty() || mode.find("[never]") != std::string::npos)
    GTEST_SKIP() << "transparent huge pages are off on this host";
  const std::string dir = temp_dir();
  std::string out;
  ASSERT_EQ(run_command("env -u GLIBC_TUNABLES " + bin("tessera") +
                            " launch --agents 2 --poses 120 --domain 62 --partition fast"
                            " --timeout 60 --heap-pages 2m --json " +
                            dir + "/s.json 2>&1",
                        &out),
            0)
      << out;
  const std::string json = slurp(dir + "/s.json");
  EXPECT_NE(json.find("\"heap_pages\": \"2m\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"fresh_page_us\": null"), std::string::npos) << json;
}

// --keep-logs keeps every process's log in the folder it names; with TESSERA_DDS_TRACE=1 each trace
// line carries the host's monotonic clock and the process's CPU time, so the processes' logs
// merge into one timeline of the start-up.
TEST(DdsLaunch, KeepLogsLeavesEveryProcesssTracedLogInTheFolder) {
  const std::string dir = temp_dir() + "/kept";  // created by launch
  std::string out;
  const int rc = run_command("TESSERA_DDS_TRACE=1 " + bin("tessera") +
                                 " launch --agents 2 --poses 60 --domain 175 --partition fast "
                                 "--timeout 60 --quiet --keep-logs " +
                                 dir + " 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("logs in " + dir + ")"), std::string::npos) << out;
  const std::regex stamp(
      R"(\[dds +[0-9.]+ @[0-9.]+ cpu [0-9.]+ tessera:[^ ]+:(coordinator|agent:[01])\] )");
  for (const char* name : {"coordinator.log", "agent0.log", "agent1.log"}) {
    const std::string log = slurp(dir + "/" + name);
    EXPECT_TRUE(std::regex_search(log, stamp)) << name << "\n" << log.substr(0, 2000);
    EXPECT_NE(log.find("barrier: passed"), std::string::npos) << name;
  }
}

// The status relay is the default; --no-status-relay turns it off, and both at once are an
// error naming them (launch and the coordinator).
TEST(DdsLaunch, StatusRelayFlagsExcludeEachOther) {
  std::string out;
  EXPECT_EQ(
      run_command(bin("tessera") + " launch --agents 3 --status-relay --no-status-relay", &out), 2)
      << out;
  EXPECT_NE(out.find("--status-relay and --no-status-relay"), std::string::npos) << out;
  EXPECT_EQ(run_command(bin("tessera-coordinator") + " --agents 3 --status-relay --no-status-relay",
                        &out),
            2)
      << out;
  EXPECT_NE(out.find("--status-relay and --no-status-relay"), std::string::npos) << out;
}

// The distributed rounding's translations (two-level pipelined PCG, relative residual 1e-12)
// are the direct solve's where that is hardest: kitti_02, a 4661-pose trajectory, 5 agents,
// positions up to ~1.5 km from pose 0. The pipelined PCG stopped on its recurrence's residual
// was 3e-6 m off; restarted from x until a residual computed from x is small enough, 1.3e-8 m
// as plain PCG (docs/dds-runtime.md, "The rounding's message steps"). Two rounds only: the rounding
// solves the same translation Laplacian whatever the rotations.
TEST(DdsLaunch, RoundingOfALongTrajectoryIsTheDirectSolves) {
  const std::string graph = std::string(TESSERA_SHARED_DIR) + "/datasets/kitti_02.g2o";
  if (!std::ifstream(graph)) GTEST_SKIP() << "no " << graph;
  const std::string dir = temp_dir();
  const std::string common =
      " --agents 5 --partition highest --algorithm irbcd --max-rounds 2 --out " + dir;
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " solve " + graph + common + "/direct.g2o 2>&1", &out), 0)
      << out;
  ASSERT_EQ(run_command(bin("tessera") + " launch " + graph + common +
                            "/dds.g2o --no-certify --domain 170 --timeout 120 2>&1",
                        &out),
            0)
      << out;
  const PoseGraph g = read_g2o(graph);
  auto poses_of = [&](const std::string& file) {
    std::string text = slurp(file);
    std::ifstream in(graph);
    for (std::string line; std::getline(in, line);)
      if (line.rfind("EDGE", 0) == 0) text += line + "\n";
    return read_g2o_text(text, file).graph.initial;
  };
  const std::vector<Pose> direct = poses_of(dir + "/direct.g2o"), dds = poses_of(dir + "/dds.g2o");
  ASSERT_EQ(direct.size(), g.num_poses);
  ASSERT_EQ(dds.size(), g.num_poses);
  double worst = 0.0;
  for (std::size_t k = 0; k < g.num_poses; ++k)
    worst = std::max(worst, (in_frame_of_pose_0(dds, k) - in_frame_of_pose_0(direct, k)).norm());
  EXPECT_LT(worst, 1e-7) << "metres, over " << g.num_poses << " poses";
}

TEST(DdsLaunch, BadGraphFailsWithTheAgentsReason) {
  const std::string dir = temp_dir();
  const std::string graph = write_file(dir, "bad.g2o", "VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 7 1 0\n");
  std::string out;
  const int rc = run_command(
      bin("tessera") + " launch " + graph + " --agents 2 --domain 164 --timeout 30 2>&1", &out);
  EXPECT_NE(rc, 0) << out;
  EXPECT_NE(out.find("failed"), std::string::npos) << out;
  EXPECT_NE(out.find("bad.g2o"), std::string::npos) << out;  // the agent's message names the file
}

TEST(DdsLaunch, SigintStopsEveryProcess) {
  const std::string dir = temp_dir();
  Process launch = start({bin("tessera"),
                          "launch",
                          "--agents",
                          "3",
                          "--poses",
                          "600",
                          "--domain",
                          "165",
                          "--grad-tol",
                          "1e-12",
                          "--max-rounds",
                          "100000",
                          "--refine",
                          "none",
                          "--progress-interval",
                          "0",
                          "--partition",
                          "fast",
                          "--timeout",
                          "60"},
                         dir + "/launch.log");
  // Wait until the rounds run, then interrupt. The signal must arrive before the run ends: the
  // Newton refinement would end it a few rounds in (a quarter of a second), and with progress
  // lines every 0.1 s the first after round 0 could be the last. Rounds alone (about a hundred)
  // with a line every round leave the interrupt a hundred rounds to spare.
  ASSERT_TRUE(wait_for_round(launch, 2, 20)) << launch.output();
  kill(launch.pid, SIGINT);
  ASSERT_TRUE(wait_all({&launch}, 15)) << launch.output();
  EXPECT_EQ(launch.exit_code, 130) << launch.output();
  EXPECT_NE(launch.output().find("interrupted"), std::string::npos) << launch.output();
  // No agent or coordinator of that run is left.
  std::string ps;
  run_command("ps -eo args | grep -c '[t]essera-agent.*--domain 165'", &ps);
  EXPECT_EQ(std::stoi(ps), 0) << ps;
}

TEST(DdsLaunch, AgentKilledDuringTheRoundsIsNamedByEveryone) {
  const std::string dir = temp_dir();
  const auto before = shm_files();
  // A run id of its own: the agent to kill is found by it, and whatever this test leaves
  // running when an assertion fails is removed by it (a leftover in the same domain would
  // otherwise be what the next run's pgrep finds).
  const std::string run_id = "killed-" + std::to_string(getpid());
  const RunCleanup cleanup{run_id};
  // 2000 poses: enough rounds (until the stalled rule stops it) that the run is still going
  // when the agent is looked up after round 2 (with 600 poses it could already have finished).
  // Lease 3 s: under ctest -j2 (load ~20) the survivors' 1 s leases of each other lapsed
  // falsely before agent 1's expired ("lost agent 2", "lost the coordinator"), so nobody named
  // agent 1; only the killed agent's 3 s lease expires.
  Process launch = start({bin("tessera"), "launch", "--agents",     "3",      "--poses",     "2000",
                          "--domain",     "166",    "--run-id",     run_id,   "--init",      "file",
                          "--grad-tol",   "1e-12",  "--max-rounds", "100000", "--partition", "fast",
                          "--timeout",    "60",     "--lease",      "3"},
                         dir + "/launch.log");
  ASSERT_TRUE(wait_for_round(launch, 2, 20)) << launch.output();
  const pid_t pid = agent_pid(run_id, 1);
  ASSERT_GT(pid, 0);
  kill(pid, SIGKILL);
  ASSERT_TRUE(wait_all({&launch}, 15)) << launch.output();
  EXPECT_EQ(launch.exit_code, 1) << launch.output();
  const std::string out = launch.output();
  EXPECT_NE(out.find("agent 1 failed"), std::string::npos) << out;
  // Who hears it first varies (lease expiry or a relayed abort); the survivors' reasons are
  // printed and name the lost agent.
  EXPECT_NE(out.find("error: lost agent 1"), std::string::npos) << out;
  EXPECT_NE(out.find("participant lease"), std::string::npos) << out;
  // The killed agent could not remove its shared-memory files; launch removed them after the
  // run (transport/fastdds/shm_leftovers.hpp): no file of this domain that no process uses is left.
  expect_launch_removed_dead_shm_files(out, before, 166);
}

// A hung agent (SIGSTOP: its DDS threads stop too, so a lease longer than the stop keeps it
// from being declared lost) is named by the coordinator's status line, with the status relay
// on (the default) and the coordinator following the agents' progress digests, not their
// round statuses: its digests stop while the others' go on from their waits
// (docs/dds-runtime.md, "Waiting, failure and shutdown"). An agent that waits for the hung
// one's pose blocks is waited for too, but its digests go on: only agent 1 is named. Once it
// goes on, so does the run.
TEST(DdsLaunch, HungAgentIsNamedAsLaggingAndTheRunGoesOn) {
  const std::string dir = temp_dir();
  const std::string run_id = "hung-" + std::to_string(getpid());
  const RunCleanup cleanup{run_id};
  Process launch = start({bin("tessera"),
                          "launch",
                          "--agents",
                          "3",
                          "--poses",
                          "2000",
                          "--domain",
                          "169",
                          "--run-id",
                          run_id,
                          "--init",
                          "file",
                          "--grad-tol",
                          "1e-12",
                          "--max-rounds",
                          "100000",
                          "--partition",
                          "fast",
                          "--timeout",
                          "90",
                          "--lease",
                          "30",
                          "--status-interval",
                          "1"},
                         dir + "/launch.log");
  ASSERT_TRUE(wait_for_round(launch, 2, 30)) << launch.output();
  const pid_t pid = agent_pid(run_id, 1);
  ASSERT_GT(pid, 0);
  kill(pid, SIGSTOP);
  // Silent for the monitor's lag_s (3 s) while the others report: named within a few seconds.
  const bool named = wait_for_output(launch, "lagging: 1", 20);
  const long stopped_at = last_progress_round(launch.output());
  kill(pid, SIGCONT);
  ASSERT_TRUE(named) << launch.output();
  const std::string lag_line = launch.output().substr(launch.output().find("lagging: 1"));
  EXPECT_EQ(lag_line.find("lagging: 1,"), std::string::npos) << lag_line;  // agent 1 only
  // It goes on from where it stopped.
  EXPECT_TRUE(wait_for_round(launch, stopped_at + 1, 30)) << launch.output();
  kill(launch.pid, SIGINT);
  ASSERT_TRUE(wait_all({&launch}, 15)) << launch.output();
  EXPECT_EQ(launch.exit_code, 130) << launch.output();
}

}  // namespace
}  // namespace tessera::test::dds
