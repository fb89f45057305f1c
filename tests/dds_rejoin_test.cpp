// Faults over DDS: an agent process SIGKILLed during the rounds and started again with the
// same options rejoins from its checkpoint; every agent rolls back to a common round and the
// run finishes with the in-process engine's result (same rounds, cost to 1e-9). Without a
// restart the coordinator gives up after --rejoin-timeout with a message naming the agent.
// A damaged checkpoint is refused with an error naming the file. In a secured run the
// restarted agent passes the peer gate before it asks to rejoin (a stalled handshake makes it
// re-create its participant, forced here) and the run still ends at the undisturbed result.
// Domains used here: 181-183 and 138 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <vector>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

std::string generate(const std::string& dir, int poses, int robots) {
  return generate_graph(dir + "/graph.g2o", "--kind grid3d --poses " + std::to_string(poses) +
                                                " --robots " + std::to_string(robots) +
                                                " --seed 3");
}

struct Fixture {
  std::string dir, graph, run, ckpt;
  int agents, domain;
  std::vector<std::string> session;       // extra options of every process (--security DIR)
  std::vector<std::string> agent_extras;  // extra options of every agent
  std::vector<std::string> agent_extra() const {
    std::vector<std::string> a = {"--timeout", "20", "--checkpoint-dir", ckpt};
    a.insert(a.end(), session.begin(), session.end());
    a.insert(a.end(), agent_extras.begin(), agent_extras.end());
    return a;
  }
  std::vector<std::string> agent_args(int k) const {
    std::vector<std::string> a = dds::agent_args(graph, agents, k, run, domain, agent_extra());
    a.insert(a.end(), {"--dump-local", dir + "/local" + std::to_string(k) + ".txt"});
    return a;
  }
  // Every agent with agent_extra() (checkpoints in ckpt) and --dump-local DIR/local<k>.txt.
  std::vector<Process> launch_agents() const {
    return start_agents(dir, graph, agents, run, domain, agent_extra(), true);
  }
  Process coordinator(double rejoin_timeout) const {
    std::vector<std::string> c = {"--timeout",
                                  "20",
                                  "--run-timeout",
                                  "50",
                                  "--summary",
                                  dir + "/summary.json",
                                  "--progress",
                                  "--partition",
                                  "eco",
                                  "--init",  // compared with the file's poses in process
                                  "file",
                                  "--grad-tol",
                                  "0.002",
                                  "--rejoin-timeout",
                                  std::to_string(rejoin_timeout),
                                  "--status-interval",
                                  "1"};
    c.insert(c.end(), session.begin(), session.end());
    return start(coordinator_args(agents, run, domain, c), dir + "/coordinator.log");
  }
};

// Waits up to wait_s for a progress line of round `round` or later in p's output, then
// SIGKILLs `victim` either way (so a failed wait leaves no agent running on); true when the
// line came.
bool kill_once_it_prints(const Process& p, long round, double wait_s, Process& victim) {
  const bool seen = wait_for_round(p, round, wait_s);
  kill(victim.pid, SIGKILL);
  return seen;
}

// Agents with checkpoints in DIR/ckpt, on a generated 300-pose graph.
Fixture make_fixture(int agents, int domain, const std::string& name) {
  Fixture f;
  f.dir = temp_dir();
  f.agents = agents;
  f.domain = domain;
  f.run = name + "-" + std::to_string(getpid());
  f.graph = generate(f.dir, 300, f.agents);
  f.ckpt = f.dir + "/ckpt";
  EXPECT_EQ(mkdir(f.ckpt.c_str(), 0755), 0);
  return f;
}

// The run's summary shows one rollback and the undisturbed run's result: the in-process
// engine with the same assignment and initial poses needs the same rounds and reaches the
// same cost (to 1e-9), because a coordinated rollback resumes bit-identical iterates.
void expect_one_rollback_then_the_undisturbed_result(const Fixture& f) {
  const std::string summary = slurp(f.dir + "/summary.json");
  EXPECT_EQ(json_field(summary, "rollbacks"), 1) << summary;
  const PoseGraph g = read_g2o(f.graph);
  const std::vector<int> assignment = assignment_of(f.dir, f.agents);
  ASSERT_EQ(assignment.size(), g.num_poses);
  DistributedOptions opt;
  opt.grad_norm_tol = 0.002;
  const DistributedResult ref = solve_distributed(g, assignment, opt, g.initial);
  EXPECT_EQ(json_field(summary, "rounds"), ref.rounds) << summary;
  EXPECT_NEAR(json_field(summary, "cost"), ref.cost, 1e-9 * ref.cost) << summary;
}

TEST(DdsRejoin, KilledAgentRestartedWithSameIdFinishesAtTheUndisturbedCost) {
  const Fixture f = make_fixture(5, 181, "rejoin");
  ASSERT_FALSE(::testing::Test::HasFailure());
  const std::string& ckpt = f.ckpt;

  Process coord = f.coordinator(20);
  std::vector<Process> agents = f.launch_agents();
  // Kill agent 2 in the middle of the rounds.
  ASSERT_TRUE(kill_once_it_prints(coord, 4, 30, agents[2])) << coord.output();
  ASSERT_TRUE(wait_all({&agents[2]}, 5));
  EXPECT_EQ(agents[2].exit_code, 128 + SIGKILL);
  Process again = start(f.agent_args(2), f.dir + "/agent2-restarted.log");

  std::vector<Process*> all = {&coord, &again};
  for (int k = 0; k < f.agents; ++k)
    if (k != 2) all.push_back(&agents[static_cast<std::size_t>(k)]);
  EXPECT_TRUE(wait_all(all, 50)) << "a process hung";
  for (Process* p : all) EXPECT_EQ(p->exit_code, 0) << p->log << ":\n" << p->output();
  EXPECT_NE(again.output().find("rejoining run"), std::string::npos) << again.output();
  const std::string co = coord.output();
  EXPECT_NE(co.find("agent 2 lost"), std::string::npos) << co;
  EXPECT_NE(co.find("agent 2 rejoined: every agent rolls back to round"), std::string::npos) << co;
  EXPECT_NE(co.find("lost: 2"), std::string::npos) << "status line names the lost agent\n" << co;

  expect_one_rollback_then_the_undisturbed_result(f);
  // Completed runs leave no checkpoint behind.
  EXPECT_FALSE(std::ifstream(ckpt + "/agent-2.ckpt").good());
}

TEST(DdsRejoin, SecuredRestartedAgentPassesThePeerGateThenRejoins) {
  if (run_command("command -v openssl", nullptr) != 0)
    GTEST_SKIP() << "openssl is not installed, skipping";
  Fixture f = make_fixture(3, 138, "secrejoin");
  ASSERT_FALSE(::testing::Test::HasFailure());
  const std::string sec = f.dir + "/sec";
  ASSERT_EQ(run_command(std::string(TESSERA_SOURCE_DIR) + "/scripts/security/make_identities.sh " +
                            sec + " 3",
                        nullptr),
            0);
  // UDP only from the start (the coordinator of a rejoin run talks UDP only): the gate's one
  // re-creation below is then the forced handshake one. Lease 2 s: secured handshakes next to
  // a loaded machine's other work made 1 s liveliness leases lapse falsely.
  f.session = {"--security", sec, "--lease", "2"};
  f.agent_extras = {"--udp-only"};

  Process coord = f.coordinator(20);
  std::vector<Process> agents = f.launch_agents();
  ASSERT_TRUE(kill_once_it_prints(coord, 4, 40, agents[1])) << coord.output();
  ASSERT_TRUE(wait_all({&agents[1]}, 5));
  // The restarted process judges the first handshake it finds unfinished stalled and
  // re-creates its participant once before asking to rejoin (a test hook outside its budget
  // for real stalls, which it may still need afterwards).
  std::vector<std::string> again_args = f.agent_args(1);
  again_args.insert(again_args.end(), {"--handshake-force-once", "--verbose"});
  Process again = start(again_args, f.dir + "/agent1-restarted.log");

  std::vector<Process*> all = {&coord, &agents[0], &agents[2], &again};
  EXPECT_TRUE(wait_all(all, 55)) << "a process hung";
  for (Process* p : all) EXPECT_EQ(p->exit_code, 0) << p->log << ":\n" << p->output();
  const std::string out = again.output();
  EXPECT_NE(out.find("rejoining run"), std::string::npos) << out;
  EXPECT_NE(out.find("re-creating this participant (forced once by a test hook"), std::string::npos)
      << out;
  EXPECT_LT(out.find("re-creating this participant"), out.find("rejoined: resuming at round"))
      << "the gate comes before the rejoin request\n"
      << out;
  const std::string co = coord.output();
  EXPECT_NE(co.find("agent 1 rejoined: every agent rolls back to round"), std::string::npos) << co;
  EXPECT_EQ(co.find("claim"), std::string::npos) << co;

  expect_one_rollback_then_the_undisturbed_result(f);
  run_command("fastdds shm clean", nullptr);
}

TEST(DdsRejoin, AgentThatDoesNotComeBackStopsTheRunAfterTheRejoinTimeout) {
  const Fixture f = make_fixture(3, 182, "norejoin");
  ASSERT_FALSE(::testing::Test::HasFailure());
  Process coord = f.coordinator(2);
  std::vector<Process> agents = f.launch_agents();
  ASSERT_TRUE(kill_once_it_prints(coord, 2, 30, agents[1])) << coord.output();
  const auto killed = Clock::now();
  std::vector<Process*> all = {&coord, &agents[0], &agents[1], &agents[2]};
  EXPECT_TRUE(wait_all(all, 30)) << "a process hung";
  const double took = std::chrono::duration<double>(Clock::now() - killed).count();
  EXPECT_EQ(coord.exit_code, 1) << coord.output();
  EXPECT_NE(coord.output().find("lost agent 1 of run"), std::string::npos) << coord.output();
  EXPECT_NE(coord.output().find("did not rejoin within 2 s"), std::string::npos) << coord.output();
  EXPECT_EQ(agents[0].exit_code, 1) << agents[0].output();
  EXPECT_EQ(agents[2].exit_code, 1) << agents[2].output();
  EXPECT_NE(agents[0].output().find("did not rejoin"), std::string::npos) << agents[0].output();
  EXPECT_GT(took, 2.0) << "the coordinator waited for the agent";
  EXPECT_LT(took, 15.0);
}

TEST(DdsRejoin, DamagedCheckpointIsRefusedNamingTheFile) {
  const std::string dir = temp_dir();
  const std::string graph = generate(dir, 60, 2);
  const std::string ckpt = dir + "/agent-0.ckpt";
  std::ofstream(ckpt) << "TSRCKPT\0 this is not a checkpoint";
  Process p =
      start(agent_args(graph, 2, 0, "damaged", 183, {"--timeout", "5", "--checkpoint-dir", dir}),
            dir + "/agent.log");
  ASSERT_TRUE(wait_all({&p}, 20));
  EXPECT_EQ(p.exit_code, 2) << p.output();
  EXPECT_NE(p.output().find(ckpt), std::string::npos) << p.output();
  EXPECT_NE(p.output().find("not usable"), std::string::npos) << p.output();
}

}  // namespace
}  // namespace tessera::test::dds
