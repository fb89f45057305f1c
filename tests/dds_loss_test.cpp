// Permanent loss over DDS: an agent SIGKILLed for good during the rounds (not restarted) has
// its block re-partitioned among the survivors, which take over its measurements from the
// replicas and finish with N-1 agents: every pose in the merged estimate, cost within 1e-6 of
// the centralized optimum, and a fault record in the summary.
// A process started again (same id) after its block was re-partitioned is refused with a
// message naming why, and the survivors' run is not disturbed.
// Every agent starts its rounds only once its holders acknowledged its replica.
// Domains used here: 186-187, 223-225 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <vector>

#include "dds_process_support.hpp"
#include "merged_estimate_checks.hpp"

namespace tessera::test::dds {
namespace {

struct LossRun {
  std::string dir, graph, run;
  int agents = 5, domain = 0;
  std::string grad_tol = "0.0005";  // --grad-tol of the coordinator
  std::string run_timeout = "50";   // --run-timeout of the coordinator (s)
  Process coordinator(int replicas, const std::vector<std::string>& extra = {}) const {
    std::vector<std::string> args = {
        "--timeout", "20", "--run-timeout", run_timeout, "--summary", dir + "/summary.json",
        "--output", dir + "/merged.g2o", "--progress", "--partition", "eco", "--grad-tol", grad_tol,
        "--replicas", std::to_string(replicas), "--replica-every", "5", "--rejoin-timeout",
        "2",  // the false-alarm window: a live peer dropped by the
              // lease on a loaded host comes back within it
        "--status-interval", "1",
        // The losses land in the rounds: with `--refine auto` these graphs hand over to the
        // refinement at gradient 30, after ~9 rounds, before the kill at round 10.
        "--refine", "none"};
    args.insert(args.end(), extra.begin(), extra.end());
    return start(coordinator_args(agents, run, domain, args), dir + "/coordinator.log");
  }
};

// Every agent's output after its log's name: a set-up that never reaches the rounds is
// explained by the agents ("no READY from agent 3" at the coordinator says who, not why).
std::string outputs_of(const std::vector<Process>& agents) {
  std::string all;
  for (const Process& a : agents) all += "\n" + a.log + ":\n" + a.output();
  return all;
}

LossRun make_run(int domain, const std::string& name, int poses = 300) {
  LossRun r;
  r.dir = temp_dir();
  r.domain = domain;
  r.run = name + "-" + std::to_string(getpid());
  r.graph = generate_graph(r.dir + "/graph.g2o", "--kind grid3d --poses " + std::to_string(poses) +
                                                     " --robots 5 --seed 3");
  return r;
}

TEST(DdsLoss, AgentKilledForGoodSurvivorsFinishAtTheOptimumWithEveryPose) {
  LossRun r = make_run(186, "loss");
  Process coord = r.coordinator(1);
  std::vector<Process> agents =
      start_agents(r.dir, r.graph, r.agents, r.run, r.domain, {"--timeout", "20", "--udp-only"},
                   false);  // --udp-only: the loss-tolerant configuration (docs/fault-tolerance.md)
  const bool started = wait_for_round(coord, 10, 30);
  kill(agents[2].pid, SIGKILL);  // for good: never restarted
  ASSERT_TRUE(started) << coord.output();
  std::vector<Process*> all = all_of(coord, agents);
  EXPECT_TRUE(wait_all(all, 50)) << "a process hung";
  EXPECT_EQ(agents[2].exit_code, 128 + SIGKILL);
  EXPECT_EQ(coord.exit_code, 0) << coord.output();
  for (int k : {0, 1, 3, 4})
    EXPECT_EQ(agents[static_cast<std::size_t>(k)].exit_code, 0)
        << agents[static_cast<std::size_t>(k)].output();
  const std::string co = coord.output();
  EXPECT_NE(co.find("re-partitioned"), std::string::npos) << co;

  // Every pose is in the merged estimate, and its cost is the centralized optimum's.
  const std::string summary = expect_every_pose_at_the_optimum(r.graph, r.dir);
  // The fault record: who was lost, who survived, what moved.
  EXPECT_NE(summary.find("\"lost_agents\": [2]"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"survivors\": [0, 1, 3, 4]"), std::string::npos) << summary;
  EXPECT_EQ(json_field(summary, "moved_poses"), 60) << summary;  // exactly agent 2's block
}

// The replica of an agent's problem goes out once, on a volatile topic: had its holder not
// received it yet (a datagram dropped under load waits for the next heartbeat's repair), an
// agent killed a few rounds later took measurements nobody else had with it ("agent 1 has
// 120 of the 150 measurements ... no surviving replica", seen once in a ctest -j2 run). Each
// agent now waits for its holders' acknowledgement before its first round, and says so.
TEST(DdsLoss, EveryAgentStartsItsRoundsOnlyOnceItsHoldersAcknowledgedItsReplica) {
  LossRun r = make_run(225, "replicaheld");
  Process coord = r.coordinator(1);
  std::vector<Process> agents = start_agents(r.dir, r.graph, r.agents, r.run, r.domain,
                                             {"--timeout", "20", "--udp-only", "--verbose"}, false);
  std::vector<Process*> all = all_of(coord, agents);
  ASSERT_TRUE(wait_all(all, 50)) << "a process hung";
  EXPECT_EQ(coord.exit_code, 0) << coord.output();
  const std::regex replicating("replicating to agent\\(s\\) ([0-9, ]+) every");
  for (std::size_t k = 0; k < agents.size(); ++k) {
    const std::string out = agents[k].output();
    EXPECT_EQ(agents[k].exit_code, 0) << out;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(out, m, replicating)) << out;
    const std::size_t held = out.find("replica held by agent(s) " + m[1].str() + " (");
    ASSERT_NE(held, std::string::npos) << out;
    EXPECT_EQ(out.find("not acknowledged"), std::string::npos) << out;
    EXPECT_LT(held, out.find("round snapshots:")) << out;  // before the round loop
  }
}

TEST(DdsLoss, WithoutReplicasALostAgentStillStopsTheRun) {
  LossRun r = make_run(187, "noreplica");
  r.agents = 3;
  // A tolerance the rounds never reach: at 5e-4 the 37-round run could end before the kill
  // landed (the first progress line is round 22 of 37), and then nothing was lost.
  r.grad_tol = "1e-12";
  generate_graph(r.graph, "--kind grid3d --poses 300 --robots 3 --seed 3");
  ASSERT_FALSE(::testing::Test::HasFailure());
  Process coord = r.coordinator(0);
  std::vector<Process> agents =
      start_agents(r.dir, r.graph, r.agents, r.run, r.domain, {"--timeout", "20"}, false);
  const bool started = wait_for_round(coord, 3, 30);
  kill(agents[1].pid, SIGKILL);
  ASSERT_TRUE(started) << coord.output();
  std::vector<Process*> all = all_of(coord, agents);
  EXPECT_TRUE(wait_all(all, 30)) << "a process hung";
  EXPECT_EQ(coord.exit_code, 1) << coord.output();
  // (On a loaded host another agent may be reported lost first; either way the run stops.)
  EXPECT_NE(coord.output().find("lost agent"), std::string::npos) << coord.output();
  EXPECT_EQ(coord.output().find("re-partitioned"), std::string::npos) << coord.output();
}

// Agent 2 is killed for good, its block re-partitioned; then a process with id 2 is started
// again (`checkpoint`: from its checkpoint, asking to rejoin; otherwise fresh). It must leave
// at once saying it was lost for good, without aborting the survivors, who finish at f*.
void restarted_after_repartition_is_refused(int domain, bool checkpoint) {
  // The refusal is the coordinator's assignment naming agent 2 lost, which a restarted process
  // can read only while the run is on. The survivors are therefore held before their results
  // (the test-only TESSERA_TEST_AGENT_HOLD, agent/test_abort_hook.hpp) until the restarted
  // process has left: however fast their rounds are, the run cannot end first. (Timed margins
  // failed here whenever the rounds got cheaper or the host busier.)
  LossRun r = make_run(domain, checkpoint ? "refused-ckpt" : "refused-fresh", 2000);
  // The kill must land in the rounds: a tolerance below the round-off floor keeps them going
  // (until the iterate stalls, a few hundred rounds), and a round limit bounds them.
  r.grad_tol = "1e-12";
  r.run_timeout = "150";
  // Lease 3 s, not 1 s: at load 32-34 a live coordinator or survivor was dropped by the 1 s
  // lease in 2 of 6 runs ("lost the coordinator ... lease of 1.0 s expired", "lost agent 1
  // after a re-partition"); the kill of agent 2 is still noticed within ~3 s.
  Process coord = r.coordinator(1, {"--max-rounds", "600", "--lease", "3"});
  const std::string released = r.dir + "/released";
  // Released however the test leaves (a failed assertion too), so no agent outlives it held.
  struct Release {
    std::string path;
    void now() const { std::ofstream(path).put('\n'); }
    ~Release() { now(); }
  } release{released};
  auto agent_argv = [&](int k) {
    std::vector<std::string> a =
        agent_args(r.graph, r.agents, k, r.run, r.domain, {"--timeout", "20", "--lease", "3"});
    if (checkpoint) a.insert(a.end(), {"--checkpoint-dir", r.dir + "/ckpt" + std::to_string(k)});
    return a;
  };
  std::vector<Process> agents;
  for (int k = 0; k < r.agents; ++k) {
    if (checkpoint) mkdir((r.dir + "/ckpt" + std::to_string(k)).c_str(), 0755);
    agents.push_back(start(with_env("TESSERA_TEST_AGENT_HOLD=" + released, agent_argv(k)),
                           r.dir + "/agent" + std::to_string(k) + ".log"));
  }
  const bool started = wait_for_round(coord, 10, 30);
  kill(agents[2].pid, SIGKILL);
  ASSERT_TRUE(started) << coord.output() << outputs_of(agents);
  // A process restarted from its checkpoint first waits 1.5 leases (4.5 s here) for its old
  // participant to expire: longer than the 2 s the coordinator waits for a rejoin, so started
  // when the loss is reported it arrives after the re-partition (asserted below), as a fresh
  // process started after the re-partition does.
  ASSERT_TRUE(wait_for_output(coord, checkpoint ? "agent 2 lost" : "re-partitioned", 30))
      << coord.output();
  Process again = start(agent_argv(2), r.dir + "/agent2-again.log");
  ASSERT_TRUE(wait_for_output(coord, "re-partitioned", 30)) << coord.output();
  const bool refused_in_time = wait_all({&again}, 30);
  release.now();  // the survivors may finish now
  ASSERT_TRUE(refused_in_time) << again.output() << "\ncoordinator:\n" << coord.output();
  EXPECT_EQ(again.exit_code, 1) << again.output();
  EXPECT_NE(again.output().find("agent 2 was lost for good in run '" + r.run +
                                "': its block was re-partitioned among the survivors (epoch 1), "
                                "so it cannot rejoin"),
            std::string::npos)
      << again.output();
  std::vector<Process*> all = {&coord};
  for (auto& a : agents) all.push_back(&a);
  EXPECT_TRUE(wait_all(all, 160)) << "a process hung";
  EXPECT_EQ(coord.exit_code, 0) << coord.output();  // not aborted by the refused process
  for (int k : {0, 1, 3, 4}) {
    const std::string out = agents[static_cast<std::size_t>(k)].output();
    EXPECT_EQ(agents[static_cast<std::size_t>(k)].exit_code, 0) << out;
    EXPECT_NE(out.find("TESSERA_TEST_AGENT_HOLD: holding the result"), std::string::npos) << out;
  }
  const PoseGraph g = read_g2o(r.graph);
  const std::string summary = slurp(r.dir + "/summary.json");
  EXPECT_NE(summary.find("\"survivors\": [0, 1, 3, 4]"), std::string::npos) << summary;
  const double fstar = solve_centralized(g).cost;
  EXPECT_LE(std::abs(json_field(summary, "cost") - fstar), 1e-6 * fstar) << summary;
}

TEST(DdsLoss, FreshProcessOfALostAgentIsRefusedAndTheSurvivorsFinish) {
  restarted_after_repartition_is_refused(223, false);
}

TEST(DdsLoss, AgentRestartedFromItsCheckpointAfterTheRepartitionIsRefused) {
  restarted_after_repartition_is_refused(224, true);
}

}  // namespace
}  // namespace tessera::test::dds
