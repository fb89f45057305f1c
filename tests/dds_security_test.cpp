// DDS Security (`--security DIR`, scripts/security/make_identities.sh): a secured run works
// end to end with the unsecured run's cost; outsiders -- a participant without identity, one
// with an identity from another CA, one from the right CA without permission for Tessera's
// topics -- read zero samples of a secured run while a permitted read-only identity reads
// it (so "zero" is not the snoop failing); agents that re-create their participant (the cure
// for a stalled handshake, forced here) still finish unread; a bad DIR is a clear error
// naming the file; outsiders without identity that advertise a member's name and tags in
// plaintext discovery data neither stop nor steer a secured run.
// Domains 193-196, 72 and 42.

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "dds_process_support.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera::test;
using namespace tessera::test::dds;

const std::string kMakeIdentities =
    std::string(TESSERA_SOURCE_DIR) + "/scripts/security/make_identities.sh";

bool have_openssl() {
  return run_command("command -v openssl", nullptr) == 0;
}

std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// One number field of a JSON summary (NaN when absent).
double json_field(const std::string& text, const std::string& key) {
  const auto at = text.find("\"" + key + "\": ");
  if (at == std::string::npos) return std::nan("");
  return std::strtod(text.c_str() + at + key.size() + 4, nullptr);
}

// "samples=K" etc. from tessera-dds-snoop's last line (-1 when absent).
long snoop_field(const std::string& out, const std::string& key) {
  const auto at = out.rfind(key + "=");
  if (at == std::string::npos) return -1;
  return std::strtol(out.c_str() + at + key.size() + 1, nullptr, 10);
}

TEST(DdsSecurity, SecuredLaunchGivesTheUnsecuredCost) {
  if (!have_openssl()) GTEST_SKIP() << "openssl is not installed, skipping";
  const std::string dir = temp_dir();
  ASSERT_EQ(run_command(kMakeIdentities + " " + dir + "/sec 3", nullptr), 0);
  std::string plain_out, secure_out;
  const std::string common = " launch --agents 3 --poses 200 --partition eco --timeout 60 --quiet";
  ASSERT_EQ(run_command(bin("tessera") + common + " --domain 193 --json " + dir + "/plain.json",
                        &plain_out),
            0)
      << plain_out;
  // No retry: a stalled Fast DDS 2.9 handshake is cured by the agents (transport/peer_gate.hpp).
  const std::string secured = bin("tessera") + common + " --domain 194 --security " + dir +
                              "/sec --json " + dir + "/secure.json";
  ASSERT_EQ(run_command(secured, &secure_out), 0) << secure_out;
  const std::string plain = read_text(dir + "/plain.json"),
                    secure = read_text(dir + "/secure.json");
  const double c0 = json_field(plain, "cost"), c1 = json_field(secure, "cost");
  ASSERT_TRUE(std::isfinite(c0) && c0 > 0) << plain;
  EXPECT_NEAR(c1, c0, 1e-9 * c0) << secure;
  EXPECT_EQ(json_field(secure, "rounds"), json_field(plain, "rounds"));
}

// What one watched secured run gave.
struct WatchedRun {
  bool stalled = false;  // a set-up wait timed out (the Fast DDS 2.9 handshake stall)
  std::string coordinator;
  std::vector<std::string> agents;  // each agent's output
};

// One secured run of 3 agents (with `agent_extra` options, and `forced_extra` for agent
// `forced_agent`) on `domain`, watched from its start
// by three outsiders and a permitted monitor. Checked here: the run finishes cleanly (or
// stalls in set-up: reported, the caller decides) and, stalled or not, no outsider reads a
// sample while the permitted monitor does.
WatchedRun secured_run_is_watched_safely(const std::string& dir, const std::string& sec,
                                         const std::string& other, const std::string& graph,
                                         int domain,
                                         const std::vector<std::string>& agent_extra = {},
                                         int forced_agent = -1,
                                         const std::vector<std::string>& forced_extra = {},
                                         bool impostors = false) {
  const std::string run = "secure-" + std::to_string(getpid()) + "-" + std::to_string(domain);
  const std::string tag = std::to_string(domain);
  struct Watcher {
    std::string name;
    std::vector<std::string> extra;
    Process p;
  };
  std::vector<Watcher> watchers = {
      {"no identity", {}, {}},
      {"another CA", {"--security", other, "--identity", "monitor"}, {}},
      {"no permission", {"--security", sec, "--identity", "nosy"}, {}},
      {"permitted monitor", {"--security", sec, "--identity", "monitor"}, {}},
  };
  if (impostors) {
    // Without identity, under run members' names (plaintext SPDP data), with tags that would
    // move the agents to UDP only if they counted (tests/dds_peer_gate_test.cpp covers a
    // "replaces" tag naming a member's real participant).
    const std::string udp = "tessera-tags;udp_only=1";
    watchers.push_back(
        {"impostor of agent 1", {"--name", "tessera:" + run + ":agent:1", "--user-data", udp}, {}});
    watchers.push_back({"impostor of the coordinator",
                        {"--name", "tessera:" + run + ":coordinator", "--user-data", udp},
                        {}});
  }
  for (auto& w : watchers) {
    std::vector<std::string> argv = {
        bin("tessera-dds-snoop"), "--domain", tag, "--run-id", run, "--duration", "90"};
    argv.insert(argv.end(), w.extra.begin(), w.extra.end());
    w.p = start(argv, dir + "/snoop_" + tag + "_" + std::to_string(&w - watchers.data()) + ".log");
  }
  bool listening = true;  // each prints "listening" once its readers exist
  for (auto& w : watchers) {
    for (int k = 0; k < 200 && w.p.output().find("listening") == std::string::npos; ++k)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (w.p.output().find("listening") == std::string::npos) {
      ADD_FAILURE() << w.name << " never listened: " << w.p.output();
      listening = false;
    }
  }

  WatchedRun result;
  bool& stalled = result.stalled;
  if (listening) {
    // Lease 3 s: with the handshakes of 8 secured participants on 2 busy cores a 1 s writer
    // liveliness lapsed falsely ("lost the coordinator", 1 of 7 looped runs at load 12).
    const std::vector<std::string> session = {"--run-id",   run, "--domain", tag, "--timeout", "20",
                                              "--security", sec, "--lease",  "3"};
    std::vector<Process> procs;
    std::vector<std::string> c = {bin("tessera-coordinator"), "--agents", "3"};
    c.insert(c.end(), session.begin(), session.end());
    procs.push_back(start(c, dir + "/coordinator_" + tag + ".log"));
    for (int k = 0; k < 3; ++k) {
      std::vector<std::string> a = {bin("tessera-agent"), "--graph", graph, "--robots", "3", "--id",
                                    std::to_string(k)};
      a.insert(a.end(), session.begin(), session.end());
      a.insert(a.end(), agent_extra.begin(), agent_extra.end());
      if (k == forced_agent) a.insert(a.end(), forced_extra.begin(), forced_extra.end());
      procs.push_back(start(a, dir + "/agent" + std::to_string(k) + "_" + tag + ".log"));
    }
    std::vector<Process*> all;
    for (auto& p : procs) all.push_back(&p);
    EXPECT_TRUE(wait_all(all, 30)) << "a process hung";
    stalled =  // any set-up wait that timed out (READY, assignment, hand-off)
        procs[0].exit_code != 0 && procs[0].output().find("timed out after") != std::string::npos;
    if (stalled) {
      std::fprintf(stderr, "secured run on domain %d stalled in set-up (known problem):\n%s\n",
                   domain, procs[0].output().c_str());
    } else {
      for (auto& p : procs) EXPECT_EQ(p.exit_code, 0) << p.output();
    }
    result.coordinator = procs[0].output();
    for (std::size_t k = 1; k < procs.size(); ++k) result.agents.push_back(procs[k].output());
  }

  for (auto& w : watchers) kill(w.p.pid, SIGINT);
  std::vector<Process*> snoops;
  for (auto& w : watchers) snoops.push_back(&w.p);
  EXPECT_TRUE(wait_all(snoops, 15)) << "a watcher hung";
  for (auto& w : watchers) {
    const std::string out = w.p.output();
    const long samples = snoop_field(out, "samples");
    if (w.name == "permitted monitor") {
      if (listening && !stalled) {
        EXPECT_GT(samples, 0) << w.name << " (the control) should read the run: " << out;
      }
    } else {
      EXPECT_EQ(samples, 0) << w.name << " read the secured run: " << out;
    }
    if (w.name == "no permission") {  // access control refuses its readers outright
      EXPECT_EQ(snoop_field(out, "refused"), 8) << out;  // every topic tessera-dds-snoop watches
    }
  }
  return result;
}

// The run's CA with 3 agents, an observer "monitor" and a participant "nosy" without
// permission in `sec`; a second CA ("Another CA") with its own 3 agents and observer in `other`.
bool make_run_and_foreign_identities(const std::string& sec, const std::string& other) {
  return run_command(kMakeIdentities + " " + sec + " 3 --observer monitor --no-permission nosy",
                     nullptr) == 0 &&
         run_command(kMakeIdentities + " " + other + " 3 --ca-name 'Another CA' --observer monitor",
                     nullptr) == 0;
}

// A test folder for a watched secured run: the run's identities go to sec, foreign ones
// (the outsiders') to other; graph is a 6 x 5 grid.
struct WatchedFolder {
  std::string dir, sec, other, graph;
};

WatchedFolder watched_folder() {
  WatchedFolder f;
  f.dir = temp_dir();
  f.sec = f.dir + "/sec";
  f.other = f.dir + "/other";
  f.graph = write_file(f.dir, "g.g2o", grid_graph_g2o(6, 5));
  return f;
}

// Every agent's closing line names a cost, and all name the same one (to the printed digits).
void expect_one_cost(const std::vector<std::string>& agent_outputs) {
  std::string cost;
  for (const std::string& out : agent_outputs) {
    const auto c = out.find(" cost ");
    ASSERT_NE(c, std::string::npos) << out;
    const std::string mine = out.substr(c, out.find(',', c) - c);
    if (cost.empty()) cost = mine;
    EXPECT_EQ(mine, cost) << out;
  }
}

TEST(DdsSecurity, OutsidersReadNothingOfASecuredRun) {
  if (!have_openssl()) GTEST_SKIP() << "openssl is not installed, skipping";
  const WatchedFolder f = watched_folder();
  ASSERT_TRUE(make_run_and_foreign_identities(f.sec, f.other));
  // Fast DDS 2.9 sometimes never completes one pair's PKI-DH handshake (about one secured
  // run in ten with 3 agents, one in two with 5, more under load; docs/dds-runtime.md,
  // "Security"). Agents now re-create their participant when that happens
  // (transport/peer_gate.hpp), so the run must finish on the first attempt: no retry.
  const WatchedRun run = secured_run_is_watched_safely(f.dir, f.sec, f.other, f.graph, 195);
  EXPECT_FALSE(run.stalled) << "the secured run stalled in set-up:\n" << run.coordinator;
  run_command("fastdds shm clean", nullptr);
}

// The cure for the stalled handshake, forced: with --handshake-force-once agent 2 judges the
// first handshake it finds unfinished stalled and re-creates its participant once. That one
// is outside its budget for real stalls (default 4 s, 3 re-creations), so a real Fast DDS 2.9
// stall after it is still cured (forced with a 1 ms stall bound and 1 retry, it was not, and a
// fresh-clone CI run timed out: "agent 1 (not authenticated; re-creations used up)"). Other
// agents only re-create to cure a real stall. The new participant replaces the old one for
// every peer (no "lost", no "two processes claim"), the run finishes, every agent reports the
// same cost, and the outsiders still read nothing.
TEST(DdsSecurity, AgentsThatRecreateTheirParticipantFinishUnreadByOutsiders) {
  if (!have_openssl()) GTEST_SKIP() << "openssl is not installed, skipping";
  const WatchedFolder f = watched_folder();
  ASSERT_TRUE(make_run_and_foreign_identities(f.sec, f.other));
  const WatchedRun run = secured_run_is_watched_safely(
      f.dir, f.sec, f.other, f.graph, 72, {}, /*forced_agent=*/2, {"--handshake-force-once"});
  ASSERT_FALSE(run.stalled) << run.coordinator;
  ASSERT_EQ(run.agents.size(), 3u);
  auto count = [](const std::string& out, const std::string& what) {
    std::size_t n = 0;
    for (auto at = out.find(what); at != std::string::npos; at = out.find(what, at + 1)) ++n;
    return n;
  };
  for (std::size_t k = 0; k < run.agents.size(); ++k) {
    const std::string& out = run.agents[k];
    // Agent 2 is forced exactly once. Besides that, every agent re-creates only as the cure
    // of a handshake really unfinished after the default 4 s (seen at load 12: agent 0 with
    // the coordinator), never for another reason.
    const std::size_t recreated = count(out, "re-creating this participant");
    const std::size_t forced = count(out, "forced once by a test hook");
    EXPECT_EQ(forced, k == 2 ? 1u : 0u) << "only agent 2 is forced, exactly once\n" << out;
    EXPECT_EQ(recreated, forced + count(out, "unfinished after 4 s")) << out;
    EXPECT_EQ(out.find("lost"), std::string::npos) << out;
  }
  expect_one_cost(run.agents);
  EXPECT_EQ(run.coordinator.find("claim"), std::string::npos) << run.coordinator;
  EXPECT_EQ(run.coordinator.find("lost"), std::string::npos) << run.coordinator;
  run_command("fastdds shm clean", nullptr);
}

// Outsiders without identity advertise agent 1's and the coordinator's participant names
// (and a tag saying "UDP only") from before the run starts to after it ends.
// Their discovery data is plaintext, so every process sees the names; a secured run counts a
// name only from an authenticated participant, so the run finishes as usual: no "two
// processes claim", no "lost", no UDP-only re-creation, one cost, and the impostors (like the
// other outsiders) read nothing.
TEST(DdsSecurity, ImpostorsOfMemberNamesNeitherStopNorSteerASecuredRun) {
  if (!have_openssl()) GTEST_SKIP() << "openssl is not installed, skipping";
  const WatchedFolder f = watched_folder();
  ASSERT_TRUE(make_run_and_foreign_identities(f.sec, f.other));
  const WatchedRun run = secured_run_is_watched_safely(f.dir, f.sec, f.other, f.graph, 42, {}, -1,
                                                       {}, /*impostors=*/true);
  ASSERT_FALSE(run.stalled) << run.coordinator;
  ASSERT_EQ(run.agents.size(), 3u);
  EXPECT_EQ(run.coordinator.find("claim"), std::string::npos) << run.coordinator;
  EXPECT_EQ(run.coordinator.find("lost"), std::string::npos) << run.coordinator;
  for (const std::string& out : run.agents) {
    EXPECT_EQ(out.find("claim"), std::string::npos) << out;
    EXPECT_EQ(out.find("lost"), std::string::npos) << out;
    EXPECT_EQ(out.find("UDP only"), std::string::npos) << out;
  }
  expect_one_cost(run.agents);
  run_command("fastdds shm clean", nullptr);
}

TEST(DdsSecurity, BadSecurityFolderNamesTheFile) {
  if (!have_openssl()) GTEST_SKIP() << "openssl is not installed, skipping";
  const std::string dir = temp_dir();
  ASSERT_EQ(run_command(kMakeIdentities + " " + dir + "/sec 2", nullptr), 0);
  ASSERT_EQ(std::remove((dir + "/sec/agent_1/key.pem").c_str()), 0);
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(4, 5));
  std::string out;
  EXPECT_EQ(
      run_command(bin("tessera-agent") + " --graph " + graph +
                      " --robots 2 --id 1 --domain 196 --timeout 2 --security " + dir + "/sec 2>&1",
                  &out),
      2);
  EXPECT_NE(out.find("agent_1/key.pem"), std::string::npos) << out;
  // A folder without the shared files: named at option parsing, by every executable.
  EXPECT_EQ(run_command(bin("tessera-coordinator") + " --agents 2 --domain 196 --security " + dir +
                            "/nowhere 2>&1",
                        &out),
            2);
  EXPECT_NE(out.find(dir + "/nowhere"), std::string::npos) << out;
  ASSERT_EQ(std::remove((dir + "/sec/governance.p7s").c_str()), 0);
  EXPECT_EQ(
      run_command(
          bin("tessera") + " launch --agents 2 --domain 196 --security " + dir + "/sec 2>&1", &out),
      2);
  EXPECT_NE(out.find("governance.p7s"), std::string::npos) << out;
}

}  // namespace
