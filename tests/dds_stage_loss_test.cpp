// Permanent loss over DDS after the rounds: an agent SIGKILLed for good during the Newton
// refinement, the distributed certificate or the distributed rounding. The survivors' waits in
// those stages end on the coordinator's re-partition (the channel raises it as in the rounds), so
// with replicas they take over the lost block, start again from their last round snapshots and
// the replica, and finish certified at the optimum with every pose; without replicas the run
// stops at once naming the lost agent. Never a hang.
// The kill is the test-only TESSERA_TEST_AGENT_KILL=STAGE@K:ID (agent/test_abort_hook.hpp),
// given through /usr/bin/env: the agent SIGKILLs itself at the K-th progress point of STAGE, so
// the loss lands in that stage on every run, however loaded the host.
// A process restarted from its checkpoint after such a kill rejoins: every agent rolls back to
// a round of the first solve stage and the run repeats the undisturbed one exactly.
// Domains used here: 86, 214, 219, 220, 227 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>
#include <utility>
#include <vector>

#include "dds_process_support.hpp"
#include "merged_estimate_checks.hpp"

namespace tessera::test::dds {
namespace {

struct StageLossRun {
  std::string dir, graph, run;
  int agents = 5, domain = 0;
  int victim = 2;
  std::string kill;  // TESSERA_TEST_AGENT_KILL of the victim
};

StageLossRun make_run(int domain, const std::string& name, const std::string& kill) {
  StageLossRun r;
  r.dir = temp_dir();
  r.domain = domain;
  r.kill = kill + ":" + std::to_string(r.victim);
  r.run = name + "-" + std::to_string(getpid());
  // 300 poses: `--refine auto` hands over to the refinement after ~9 rounds (gradient 30),
  // and the certificate holds at rank 5 after it.
  r.graph = generate_graph(r.dir + "/graph.g2o", "--kind grid3d --poses 300 --robots 5 --seed 3");
  return r;
}

// Coordinator (certified, `--refine auto`) and agents; `replicas` > 0: the loss-tolerant
// configuration of tests/dds_loss_test.cpp. Waits for every process; true when none hung.
bool run_with_a_kill(const StageLossRun& r, int replicas, Process& coord,
                     std::vector<Process>& agents) {
  std::vector<std::string> c = {"--timeout",
                                "20",
                                "--run-timeout",
                                "60",
                                "--summary",
                                r.dir + "/summary.json",
                                "--output",
                                r.dir + "/merged.g2o",
                                "--progress",
                                "--partition",
                                "eco",
                                "--grad-tol",
                                "0.0005",
                                "--certify",
                                "--refine",
                                "auto",
                                "--status-interval",
                                "1"};
  if (replicas > 0)
    c.insert(c.end(), {"--replicas", std::to_string(replicas), "--replica-every", "5",
                       "--rejoin-timeout", "2"});
  coord = start(coordinator_args(r.agents, r.run, r.domain, c), r.dir + "/coordinator.log");
  for (int k = 0; k < r.agents; ++k) {
    std::vector<std::string> a =
        agent_args(r.graph, r.agents, k, r.run, r.domain, {"--timeout", "20", "--udp-only"});
    if (k == r.victim) a = with_env("TESSERA_TEST_AGENT_KILL=" + r.kill, std::move(a));
    agents.push_back(start(a, r.dir + "/agent" + std::to_string(k) + ".log"));
  }
  return wait_all(all_of(coord, agents), 60);
}

std::string outputs_of(const Process& coord, const std::vector<Process>& agents) {
  std::string all = coord.log + ":\n" + coord.output();
  for (const Process& a : agents) all += "\n" + a.log + ":\n" + a.output();
  return all;
}

// The victim died where it was told to, every survivor and the coordinator ended with 0, the
// block was re-partitioned, and the merged estimate has every pose, at f*, certified.
void expect_certified_optimum_after_loss_in(int domain, const std::string& name,
                                            const std::string& kill, const std::string& stage) {
  const StageLossRun r = make_run(domain, name, kill);
  ASSERT_FALSE(::testing::Test::HasFailure());
  Process coord;
  std::vector<Process> agents;
  agents.reserve(static_cast<std::size_t>(r.agents));
  ASSERT_TRUE(run_with_a_kill(r, 1, coord, agents)) << "a process hung\n"
                                                    << outputs_of(coord, agents);
  const Process& victim = agents[static_cast<std::size_t>(r.victim)];
  ASSERT_EQ(victim.exit_code, 128 + SIGKILL) << victim.output();
  EXPECT_NE(victim.output().find("killed in the " + stage), std::string::npos) << victim.output();
  EXPECT_EQ(coord.exit_code, 0) << outputs_of(coord, agents);
  for (int k = 0; k < r.agents; ++k) {
    if (k == r.victim) continue;
    const Process& a = agents[static_cast<std::size_t>(k)];
    EXPECT_EQ(a.exit_code, 0) << a.output();
  }
  EXPECT_NE(coord.output().find("re-partitioned"), std::string::npos) << coord.output();
  const std::string summary = expect_every_pose_at_the_optimum(r.graph, r.dir);
  EXPECT_NE(summary.find("\"certified\": true"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"lost_agents\": [2]"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"survivors\": [0, 1, 3, 4]"), std::string::npos) << summary;
}

TEST(DdsStageLoss, AgentKilledInTheRefinementSurvivorsFinishCertifiedAtTheOptimum) {
  expect_certified_optimum_after_loss_in(214, "refineloss", "refinement@5", "refinement");
}

TEST(DdsStageLoss, AgentKilledInTheCertificateSurvivorsFinishCertifiedAtTheOptimum) {
  expect_certified_optimum_after_loss_in(219, "certloss", "certificate@1", "certificate");
}

TEST(DdsStageLoss, AgentKilledInTheRoundingSurvivorsFinishCertifiedAtTheOptimum) {
  expect_certified_optimum_after_loss_in(220, "roundloss", "rounding@1", "rounding");
}

// Without replicas nobody can take the block over: the refinement's collective steps do not
// wait for the dead peer, the run stops within the lease and says who was lost (exit 1).
TEST(DdsStageLoss, AgentKilledInTheRefinementWithoutReplicasStopsTheRunNamingIt) {
  const StageLossRun r = make_run(227, "refinestop", "refinement@5");
  ASSERT_FALSE(::testing::Test::HasFailure());
  Process coord;
  std::vector<Process> agents;
  agents.reserve(static_cast<std::size_t>(r.agents));
  ASSERT_TRUE(run_with_a_kill(r, 0, coord, agents)) << "a process hung\n"
                                                    << outputs_of(coord, agents);
  ASSERT_EQ(agents[2].exit_code, 128 + SIGKILL) << agents[2].output();
  EXPECT_EQ(coord.exit_code, 1) << coord.output();
  // (On a loaded host another agent may be reported lost first; either way the run stops.)
  EXPECT_NE(coord.output().find("lost agent"), std::string::npos) << coord.output();
  for (int k : {0, 1, 3, 4})
    EXPECT_EQ(agents[static_cast<std::size_t>(k)].exit_code, 1)
        << agents[static_cast<std::size_t>(k)].output();
}

// Killed in the refinement and started again from its checkpoint (a supervisor's restart): the
// coordinator orders a rollback to the newest checkpoint round every agent has reached (the
// refinement keeps no snapshots, so a round of the first solve stage), and the run ends with the
// undisturbed run's cost to the last digit, certified.
TEST(DdsStageLoss, AgentKilledInTheRefinementRejoinsFromItsCheckpointWithTheUndisturbedResult) {
  const StageLossRun r = make_run(86, "refinerejoin", "refinement@5");
  ASSERT_FALSE(::testing::Test::HasFailure());
  const auto coordinator = [&](const std::string& tag) {
    return start(
        coordinator_args(r.agents, r.run + tag, r.domain,
                         {"--timeout", "20", "--run-timeout", "60", "--summary",
                          r.dir + "/summary" + tag + ".json", "--partition", "eco", "--grad-tol",
                          "0.0005", "--certify", "--refine", "auto", "--rejoin-timeout", "20"}),
        r.dir + "/coordinator" + tag + ".log");
  };
  const auto agent_argv = [&](const std::string& tag, int k) {
    const std::string ckpt = r.dir + "/ckpt" + tag + std::to_string(k);
    mkdir(ckpt.c_str(), 0755);
    return agent_args(r.graph, r.agents, k, r.run + tag, r.domain,
                      {"--timeout", "20", "--udp-only", "--checkpoint-dir", ckpt});
  };
  const auto run = [&](const std::string& tag, bool kill) {
    Process coord = coordinator(tag);
    std::vector<Process> agents;
    agents.reserve(static_cast<std::size_t>(r.agents) + 1);
    for (int k = 0; k < r.agents; ++k) {
      std::vector<std::string> a = agent_argv(tag, k);
      if (kill && k == r.victim) a = with_env("TESSERA_TEST_AGENT_KILL=" + r.kill, std::move(a));
      agents.push_back(start(a, r.dir + "/agent" + tag + std::to_string(k) + ".log"));
    }
    if (kill) {
      Process& victim = agents[static_cast<std::size_t>(r.victim)];
      EXPECT_TRUE(wait_all({&victim}, 30)) << victim.output();
      EXPECT_EQ(victim.exit_code, 128 + SIGKILL) << victim.output();
      EXPECT_NE(victim.output().find("killed in the refinement"), std::string::npos)
          << victim.output();
      agents.push_back(start(agent_argv(tag, r.victim),
                             r.dir + "/agent" + tag + std::to_string(r.victim) + "-again.log"));
    }
    EXPECT_TRUE(wait_all(all_of(coord, agents), 60)) << "a process hung\n"
                                                     << outputs_of(coord, agents);
    EXPECT_EQ(coord.exit_code, 0) << outputs_of(coord, agents);
    for (std::size_t k = 0; k < agents.size(); ++k) {
      if (kill && k == static_cast<std::size_t>(r.victim)) continue;  // SIGKILLed
      EXPECT_EQ(agents[k].exit_code, 0) << agents[k].output();
    }
    return std::make_pair(coord.output(), slurp(r.dir + "/summary" + tag + ".json"));
  };
  const auto [co, disturbed] = run("-killed", true);
  EXPECT_NE(co.find("rejoined: every agent rolls back to round"), std::string::npos) << co;
  const auto [co0, undisturbed] = run("-undisturbed", false);
  EXPECT_NE(disturbed.find("\"certified\": true"), std::string::npos) << disturbed;
  const auto cost_of = [](const std::string& summary) {
    const std::size_t at = summary.find("\"cost\": ");
    return at == std::string::npos ? std::string() : summary.substr(at, summary.find(',', at) - at);
  };
  ASSERT_FALSE(cost_of(undisturbed).empty()) << undisturbed;
  EXPECT_EQ(cost_of(disturbed), cost_of(undisturbed)) << disturbed << "\n" << undisturbed;
}

}  // namespace
}  // namespace tessera::test::dds
