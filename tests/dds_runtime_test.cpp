// The DDS runtime end to end on one host: tessera-coordinator and tessera-agent processes
// on a graph the test writes. Every test uses its own DDS domain (and run id) so tests may
// run in parallel, and finishes in seconds; no process outlives its test.

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <sstream>

#include "dds_process_support.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera::test;
using namespace tessera::test::dds;

std::string agent_bin() {
  return bin("tessera-agent");
}
std::string coordinator_bin() {
  return bin("tessera-coordinator");
}

std::string unique_run(const std::string& stem) {
  return stem + "-" + std::to_string(getpid());
}

// Parsed agent dump (--dump-local).
struct Dump {
  long structure = -1;
  std::set<int> owned;
  std::map<long, std::vector<double>> meas;  // file index -> i j kappa tau R t
  std::map<int, std::vector<double>> poses;
};

Dump read_dump(const std::string& path) {
  Dump d;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    std::istringstream ss(line);
    std::string tag;
    ss >> tag;
    if (tag == "STRUCTURE") {
      ss >> d.structure;
    } else if (tag == "OWNED") {
      int id;
      ss >> id;
      d.owned.insert(id);
    } else if (tag == "MEAS") {
      long k;
      ss >> k;
      double x;
      while (ss >> x) d.meas[k].push_back(x);
    } else if (tag == "POSE") {
      int id;
      ss >> id;
      double x;
      while (ss >> x) d.poses[id].push_back(x);
    }
  }
  return d;
}

// Measurements of the g2o text, in file order: (i, j, dx, dy, dtheta).
std::vector<std::array<double, 5>> edges_of(const std::string& g2o) {
  std::vector<std::array<double, 5>> out;
  std::istringstream in(g2o);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string tag;
    ss >> tag;
    if (tag != "EDGE_SE2") continue;
    std::array<double, 5> e{};
    for (double& x : e) ss >> x;
    out.push_back(e);
  }
  return out;
}

// Merged g2o output of the coordinator: id -> (x, y, theta).
std::map<int, std::array<double, 3>> vertices_of(const std::string& path) {
  std::map<int, std::array<double, 3>> out;
  std::ifstream f(path);
  std::string tag;
  while (f >> tag) {
    if (tag != "VERTEX_SE2") {
      std::string rest;
      std::getline(f, rest);
      continue;
    }
    int id;
    std::array<double, 3> v{};
    f >> id >> v[0] >> v[1] >> v[2];
    out[id] = v;
  }
  return out;
}

TEST(DdsRuntime, OneHostRunHandsOffEveryMeasurementAndMergesEveryPose) {
  const std::string dir = temp_dir();
  const int domain = 141;
  const std::string run = unique_run("onehost");
  std::vector<std::array<double, 3>> truth;
  const std::string text = grid_graph_g2o(7, 11, &truth);
  const std::string graph = write_file(dir, "grid.g2o", text);
  const auto before = shm_files();

  Process coord = start(coordinator_args(3, run, domain,
                                         {"--timeout", "20", "--output", dir + "/merged.g2o",
                                          "--summary", dir + "/summary.json", "--verbose", "--init",
                                          "file"}),  // the file's poses travel
                        dir + "/coordinator.log");
  std::vector<Process> agents;
  for (int k = 0; k < 3; ++k)
    agents.push_back(start(agent_args(graph, 3, k, run, domain,
                                      {"--timeout", "20", "--dump-local",
                                       dir + "/local" + std::to_string(k) + ".txt"}),
                           dir + "/agent" + std::to_string(k) + ".log"));
  std::vector<Process*> all = {&coord, &agents[0], &agents[1], &agents[2]};
  ASSERT_TRUE(wait_all(all, 30)) << "a process hung";
  for (Process* p : all) ASSERT_EQ(p->exit_code, 0) << p->output();

  // Owners from the dumps: every pose owned by exactly one agent.
  std::vector<Dump> dumps;
  std::map<int, int> owner;
  for (int k = 0; k < 3; ++k) {
    dumps.push_back(read_dump(dir + "/local" + std::to_string(k) + ".txt"));
    for (int id : dumps[k].owned) {
      EXPECT_EQ(owner.count(id), 0u) << "pose " << id << " owned twice";
      owner[id] = k;
    }
  }
  ASSERT_EQ(owner.size(), truth.size());
  // The partition moved some poses away from the robot that read them (ids are shuffled),
  // so initial poses really travelled.
  int moved = 0;
  for (auto [id, k] : owner)
    if (k != id * 3 / static_cast<int>(truth.size())) ++moved;
  EXPECT_GT(moved, 0);

  // Every measurement is at the owners of both endpoints, with its values, and nowhere else.
  const auto edges = edges_of(text);
  for (const Dump& d : dumps) EXPECT_EQ(d.structure, static_cast<long>(edges.size()));
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const int i = static_cast<int>(edges[k][0]), j = static_cast<int>(edges[k][1]);
    for (int a = 0; a < 3; ++a) {
      const bool should = owner[i] == a || owner[j] == a;
      auto it = dumps[a].meas.find(static_cast<long>(k));
      ASSERT_EQ(it != dumps[a].meas.end(), should)
          << "measurement #" << k << " (" << i << "," << j << ") at agent " << a;
      if (!should) continue;
      const auto& v = it->second;  // i j kappa tau R(4) t(2)
      ASSERT_EQ(v.size(), 10u);
      EXPECT_EQ(v[0], i);
      EXPECT_EQ(v[1], j);
      EXPECT_NEAR(v[8], edges[k][2], 1e-12);
      EXPECT_NEAR(v[9], edges[k][3], 1e-12);
      EXPECT_NEAR(std::atan2(v[5], v[4]), edges[k][4], 1e-12);
    }
  }
  // Initial poses arrived at their owners.
  for (int a = 0; a < 3; ++a)
    for (int id : dumps[a].owned) {
      ASSERT_EQ(dumps[a].poses.count(id), 1u);
      EXPECT_NEAR(dumps[a].poses[id][4], truth[id][0], 1e-12);
      EXPECT_NEAR(dumps[a].poses[id][5], truth[id][1], 1e-12);
    }

  // The merged result has every pose. The graph is noise free and starts at the truth, so the
  // solve keeps it; rounding fixes pose 0 at the origin and picks its own rotation frame, so
  // compare relative poses along every measurement.
  auto merged = vertices_of(dir + "/merged.g2o");
  ASSERT_EQ(merged.size(), truth.size());
  auto relative = [](double xi, double yi, double ti, double xj, double yj, double tj) {
    const double c = std::cos(ti), s = std::sin(ti);
    return std::array<double, 3>{c * (xj - xi) + s * (yj - yi), -s * (xj - xi) + c * (yj - yi),
                                 std::remainder(tj - ti, 2 * M_PI)};
  };
  for (const auto& e : edges) {
    const int i = static_cast<int>(e[0]), j = static_cast<int>(e[1]);
    ASSERT_TRUE(merged.count(i) && merged.count(j));
    const auto got = relative(merged[i][0], merged[i][1], merged[i][2], merged[j][0], merged[j][1],
                              merged[j][2]);
    const auto want =
        relative(truth[i][0], truth[i][1], truth[i][2], truth[j][0], truth[j][1], truth[j][2]);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], want[c], 1e-6) << "edge " << i << "-" << j;
  }
  std::ifstream summary(dir + "/summary.json");
  std::stringstream ss;
  ss << summary.rdbuf();
  EXPECT_NE(ss.str().find("\"discovery_ms\""), std::string::npos);
  EXPECT_NE(ss.str().find("\"bytes_sent\""), std::string::npos);
  EXPECT_TRUE(leaked_shm_files(before, domain).empty()) << join(leaked_shm_files(before, domain));
}

// `transport`: extra session options of every process (e.g. --transport shm).
void two_concurrent_runs_on_one_domain(int domain, const std::vector<std::string>& transport) {
  // Same domain on purpose (the harder case): only Partition QoS and the run id keep them apart.
  const std::string dir = temp_dir();
  const std::string graph_a = write_file(dir, "a.g2o", grid_graph_g2o(5, 1));
  const std::string graph_b = write_file(dir, "b.g2o", grid_graph_g2o(6, 2));
  std::vector<std::string> session = {"--timeout", "20"};
  session.insert(session.end(), transport.begin(), transport.end());
  std::vector<Process> procs;
  for (const auto& [run, graph] :
       {std::make_pair(unique_run("runA"), graph_a), std::make_pair(unique_run("runB"), graph_b)}) {
    std::vector<std::string> coordinator = session;
    coordinator.insert(coordinator.end(), {"--output", dir + "/" + run + ".g2o"});
    procs.push_back(
        start(coordinator_args(2, run, domain, coordinator), dir + "/" + run + "_coordinator.log"));
    for (int k = 0; k < 2; ++k)
      procs.push_back(start(agent_args(graph, 2, k, run, domain, session),
                            dir + "/" + run + "_agent" + std::to_string(k) + ".log"));
  }
  std::vector<Process*> all;
  for (auto& p : procs) all.push_back(&p);
  ASSERT_TRUE(wait_all(all, 30));
  // Every process's log on failure: the failing coordinator names only whom it missed, the
  // missed agent says what it waited for (and names a stuck shared-memory listener,
  // transport/fastdds/shm_receive_watch.hpp).
  bool all_ok = true;
  for (Process* p : all) {
    EXPECT_EQ(p->exit_code, 0) << p->log << ":\n" << p->output();
    all_ok = all_ok && p->exit_code == 0;
  }
  ASSERT_TRUE(all_ok);
  EXPECT_EQ(vertices_of(dir + "/" + unique_run("runA") + ".g2o").size(), 25u);
  EXPECT_EQ(vertices_of(dir + "/" + unique_run("runB") + ".g2o").size(), 36u);
}

TEST(DdsRuntime, TwoConcurrentRunsOnOneDomainDoNotMix) {
  two_concurrent_runs_on_one_domain(142, {});
}

TEST(DdsRuntime, TwoConcurrentRunsOnOneDomainDoNotMixOverSharedMemoryOnly) {
  // Discovery too goes over shared-memory ports then (tessera launch's default).
  two_concurrent_runs_on_one_domain(148, {"--transport", "shm"});
}

void killed_agent_is_named(int domain, const std::vector<std::string>& transport) {
  const std::string dir = temp_dir();
  const std::string run = unique_run("kill");
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(6, 3));
  const auto before = shm_files();
  // The coordinator waits for a 4th agent that never comes, so the others are mid-run
  // (waiting) when agent 1 is killed. Lease 2 s: under ctest -j2 a survivor's 1 s lease can
  // lapse falsely first, and then the others name it instead of agent 1 (seen in CI in the
  // launch version of this test, DdsLaunch.AgentKilledDuringTheRoundsIsNamedByEveryone).
  std::vector<std::string> session = {"--timeout", "30", "--lease", "2"};
  session.insert(session.end(), transport.begin(), transport.end());
  Process coord = start(coordinator_args(4, run, domain, session), dir + "/coordinator.log");
  std::vector<Process> agents;
  for (int k = 0; k < 3; ++k)
    agents.push_back(start(agent_args(graph, 4, k, run, domain, session),
                           dir + "/agent" + std::to_string(k) + ".log"));
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));
  for (Process* p : {&coord, &agents[0], &agents[1], &agents[2]}) {
    int status;
    ASSERT_EQ(waitpid(p->pid, &status, WNOHANG), 0) << "exited early: " << p->output();
  }
  kill(agents[1].pid, SIGKILL);
  const auto killed_at = Clock::now();
  ASSERT_TRUE(wait_all({&agents[1]}, 5));
  std::vector<Process*> survivors = {&coord, &agents[0], &agents[2]};
  ASSERT_TRUE(wait_all(survivors, 10)) << "a survivor hung";
  const double took = std::chrono::duration<double>(Clock::now() - killed_at).count();
  EXPECT_LT(took, 5.0);
  for (Process* p : survivors) {
    EXPECT_NE(p->exit_code, 0) << p->output();
    EXPECT_NE(p->output().find("lost agent 1"), std::string::npos) << p->output();
  }
  // A SIGKILLed participant leaks its shared memory by nature; remove what nobody uses.
  remove_shm_files(leaked_shm_files(before, domain));
  // Its segment files too (`fastdds shm clean` only removes segments nobody holds).
  run_command("fastdds shm clean", nullptr);
}

TEST(DdsRuntime, KilledAgentIsNamedAndEveryoneStopsNonZero) {
  killed_agent_is_named(143, {});
}

TEST(DdsRuntime, KilledAgentIsNamedOverSharedMemoryOnly) {
  // Nothing but the lease tells the survivors: no UDP, and the dead agent's ports stay.
  killed_agent_is_named(149, {"--transport", "shm"});
}

// Signals go to one process only: with several, which process stops first (and so
// whose reason the others report) is a race.
void signal_one_process(int domain, const std::string& stem, int target, int signo,
                        const std::vector<std::string>& transport = {}) {
  const std::string dir = temp_dir();
  const std::string run = unique_run(stem);
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(5, 4));
  const auto before = shm_files();
  // Three agents of four: everybody is waiting (mid-run) when the signal comes. --verbose
  // prints the events waited for below.
  std::vector<std::string> session = {"--timeout", "30", "--verbose"};
  session.insert(session.end(), transport.begin(), transport.end());
  std::vector<Process> procs;
  procs.push_back(start(coordinator_args(4, run, domain, session), dir + "/coordinator.log"));
  for (int k = 0; k < 3; ++k)
    procs.push_back(start(agent_args(graph, 4, k, run, domain, session),
                          dir + "/agent" + std::to_string(k) + ".log"));
  // The signal goes out once every process is mid-run: the coordinator has discovered the
  // three agents and each agent has announced itself. A fixed delay (it was 1.5 s) assumes the
  // start-up fits in it, which heavy load need not grant: a process signalled before its main()
  // blocks the signal dies without telling the others, who then wait for their --timeout.
  const auto mid_run = [&] {
    for (int k = 0; k < 3; ++k)
      if (procs[0].output().find("discovered agent " + std::to_string(k)) == std::string::npos ||
          procs[static_cast<std::size_t>(k) + 1].output().find("announced") == std::string::npos)
        return false;
    return true;
  };
  const auto started = std::chrono::steady_clock::now();
  while (!mid_run()) {
    // Hang detector only: the start-up takes 1-2 s, far longer only under extreme load.
    ASSERT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(60))
        << "not mid-run after 60 s: " << procs[0].output();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(procs[target].pid, signo);
  std::vector<Process*> all;
  for (auto& p : procs) all.push_back(&p);
  // A hang detector, not a speed test: the stop's own bounded waits add up to ~8 s per process
  // (the ABORT's linger, up to 3 s, then the participant's deletion, given 5 s before the
  // teardown guard ends it), each longer under load. A signal that stopped nothing would end
  // in the --timeout (30 s) with "timed out" instead of the message checked below.
  ASSERT_TRUE(wait_all(all, 60)) << "did not stop after the signal";
  const std::string name = signo == SIGINT ? "SIGINT" : "SIGTERM";
  const std::string who = target == 0 ? "coordinator" : "agent " + std::to_string(target - 1);
  for (std::size_t k = 0; k < procs.size(); ++k) {
    const std::string out = procs[k].output();
    if (static_cast<int>(k) == target) {
      EXPECT_EQ(procs[k].exit_code, 128 + signo) << out;
    } else {
      EXPECT_EQ(procs[k].exit_code, 1) << out;
      EXPECT_NE(out.find(who), std::string::npos) << out;
    }
    // Stopped by the signal, not by the --timeout.
    EXPECT_NE(out.find("interrupted by " + name), std::string::npos) << out;
  }
  const auto leaked = leaked_shm_files(before, domain);
  EXPECT_TRUE(leaked.empty()) << "left in /dev/shm: " << join(leaked);
}

TEST(DdsRuntime, SigintToCoordinatorStopsTheRunCleanlyWithoutSharedMemoryLeft) {
  signal_one_process(144, "sigint", 0, SIGINT);
}

TEST(DdsRuntime, SigtermToAgentStopsTheRunCleanlyWithoutSharedMemoryLeft) {
  signal_one_process(147, "sigterm", 2, SIGTERM);
}

TEST(DdsRuntime, SigtermToAgentOverSharedMemoryOnlyStopsTheRunWithoutSharedMemoryLeft) {
  signal_one_process(155, "sigterm-shm", 2, SIGTERM, {"--transport", "shm"});
}

TEST(DdsRuntime, AgentWithBadFileFailsClearlyAndTheOthersStop) {
  const std::string dir = temp_dir();
  const int domain = 145;
  const std::string run = unique_run("badfile");
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(5, 5));
  const std::string bad = write_file(dir, "bad.g2o", "VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 oops\n");
  const auto before = shm_files();
  Process coord =
      start(coordinator_args(3, run, domain, {"--timeout", "30"}), dir + "/coordinator.log");
  Process a0 =
      start(agent_args(graph, 3, 0, run, domain, {"--timeout", "30"}), dir + "/agent0.log");
  Process a2 =
      start(agent_args(graph, 3, 2, run, domain, {"--timeout", "30"}), dir + "/agent2.log");
  Process a1 = start(agent_args(bad, 3, 1, run, domain, {"--timeout", "30"}), dir + "/agent1.log");
  ASSERT_TRUE(wait_all({&coord, &a0, &a1, &a2}, 10)) << "a process hung";
  EXPECT_EQ(a1.exit_code, 2) << a1.output();
  EXPECT_NE(a1.output().find("bad.g2o:2:"), std::string::npos) << a1.output();
  // The coordinator names the bad-file agent and its cause, whoever's ABORT reached it
  // first (agent 1's own or one relayed by another agent): agents wait for the coordinator
  // to acknowledge their abort before leaving. The other agents stop too; they usually name
  // the cause as well, but on a heavily loaded machine an agent may not have discovered
  // agent 1 (nor anyone relaying its abort) before they left, and then reports whom it lost.
  EXPECT_NE(coord.output().find("tessera-coordinator: error: agent 1 aborted run '" + run +
                                "': " + bad + ":2: "),
            std::string::npos)
      << coord.output();
  for (Process* p : {&coord, &a0, &a2}) {
    EXPECT_EQ(p->exit_code, 1) << p->output();
    EXPECT_NE(p->output().find("error: "), std::string::npos) << p->output();
    EXPECT_LT(p->exit_after_s, 8.0) << p->output();
  }
  const auto leaked = leaked_shm_files(before, domain);
  EXPECT_TRUE(leaked.empty()) << "left in /dev/shm: " << join(leaked);
}

TEST(DdsRuntime, CoordinatorTimesOutNamingTheMissingAgents) {
  const std::string dir = temp_dir();
  const int domain = 146;
  const std::string run = unique_run("missing");
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(5, 6));
  Process coord =
      start(coordinator_args(3, run, domain, {"--timeout", "2"}), dir + "/coordinator.log");
  Process a0 =
      start(agent_args(graph, 3, 0, run, domain, {"--timeout", "30"}), dir + "/agent0.log");
  ASSERT_TRUE(wait_all({&coord, &a0}, 10));
  EXPECT_EQ(coord.exit_code, 1);
  EXPECT_NE(coord.output().find("timed out after 2 s waiting for 3 agents"), std::string::npos)
      << coord.output();
  EXPECT_NE(coord.output().find("missing agent 1, 2 (have agent 0)"), std::string::npos)
      << coord.output();
  EXPECT_EQ(a0.exit_code, 1) << a0.output();
}

TEST(DdsRuntime, ExecutablesExplainTheirOptions) {
  std::string out;
  EXPECT_EQ(run_command(agent_bin() + " --help", &out), 0);
  EXPECT_NE(out.find("--run-id"), std::string::npos);
  EXPECT_EQ(run_command(coordinator_bin() + " --help", &out), 0);
  EXPECT_NE(out.find("--domain"), std::string::npos);
  EXPECT_EQ(run_command(agent_bin() + " --graph x.g2o --robots 2", &out), 2);
  EXPECT_NE(out.find("--id is required"), std::string::npos) << out;
  EXPECT_EQ(run_command(coordinator_bin() + " --agents 2 --bogus 1", &out), 2);
  EXPECT_NE(out.find("unknown option --bogus"), std::string::npos) << out;
  EXPECT_EQ(run_command(coordinator_bin() + " --agents 2 --run-id 'a b'", &out), 2);
  EXPECT_NE(out.find("--run-id"), std::string::npos) << out;
}

}  // namespace
