// The DDS runtime across "hosts": network namespaces joined by veth pairs and a bridge
// (scripts/netns/netns.sh; addresses only inside namespaces this test creates, always
// removed afterwards). Skips with a message where namespaces cannot be created.

#include <gtest/gtest.h>

#include "dds_process_support.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera::test;
using namespace tessera::test::dds;

const std::string kScript = std::string(TESSERA_SOURCE_DIR) + "/scripts/netns/netns.sh";

bool namespaces_available(std::string* why) {
  if (geteuid() != 0) {
    *why = "not root";
    return false;
  }
  std::string out;
  if (run_command(kScript + " check", &out) != 0) {
    *why = out;
    return false;
  }
  return true;
}

// Four namespaces (coordinator + 3 agents), removed when the test ends, however it ends.
class Hosts {
 public:
  explicit Hosts(bool block_multicast) {
    const int tag = static_cast<int>(getpid() % 100000);
    prefix_ = "tss" + std::to_string(tag);
    subnet_ = "10.77." + std::to_string(20 + tag % 200);
    std::string out;
    ok_ = run_command(kScript + " up " + prefix_ + " 4 " + subnet_ +
                          (block_multicast ? " --block-multicast" : ""),
                      &out) == 0;
    error_ = out;
  }
  ~Hosts() { run_command(kScript + " down " + prefix_, nullptr); }
  bool ok() const { return ok_; }
  const std::string& error() const { return error_; }
  std::vector<std::string> in(int host, std::vector<std::string> argv,
                              const std::string& env = "") const {
    std::vector<std::string> a = {"/usr/bin/env"};
    if (!env.empty()) a.push_back(env);
    for (const char* w : {"ip", "netns", "exec"}) a.push_back(w);
    a.push_back(prefix_ + "-" + std::to_string(host));
    a.insert(a.end(), argv.begin(), argv.end());
    return a;
  }
  std::string addresses() const {
    return subnet_ + ".1," + subnet_ + ".2," + subnet_ + ".3," + subnet_ + ".4";
  }
  std::string address(int host) const { return subnet_ + "." + std::to_string(host + 1); }

 private:
  std::string prefix_, subnet_, error_;
  bool ok_ = false;
};

// Coordinator on host 0, agent k on host k+1; returns the processes after they ended.
std::vector<Process> run_across_hosts(const Hosts& hosts, const std::string& dir,
                                      const std::string& graph, int domain, const std::string& run,
                                      double timeout_s, const std::vector<std::string>& extra,
                                      const std::string& env = "") {
  std::vector<Process> procs;
  std::vector<std::string> c = coordinator_args(
      3, run, domain,
      {"--timeout", std::to_string(timeout_s), "--output", dir + "/" + run + ".g2o"});
  c.insert(c.end(), extra.begin(), extra.end());
  procs.push_back(start(hosts.in(0, c, env), dir + "/" + run + "_coordinator.log"));
  for (int k = 0; k < 3; ++k) {
    std::vector<std::string> a =
        agent_args(graph, 3, k, run, domain, {"--timeout", std::to_string(timeout_s)});
    a.insert(a.end(), extra.begin(), extra.end());
    procs.push_back(
        start(hosts.in(k + 1, a, env), dir + "/" + run + "_agent" + std::to_string(k) + ".log"));
  }
  std::vector<Process*> all;
  for (auto& p : procs) all.push_back(&p);
  EXPECT_TRUE(wait_all(all, timeout_s + 10)) << "a process hung";
  return procs;
}

TEST(DdsNetns, RunAcrossNamespacesWithMulticastDiscovery) {
  std::string why;
  if (!namespaces_available(&why))
    GTEST_SKIP() << "network namespaces unavailable here, skipping: " << why;
  Hosts hosts(false);
  ASSERT_TRUE(hosts.ok()) << hosts.error();
  const std::string dir = temp_dir();
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(6, 7));
  auto procs =
      run_across_hosts(hosts, dir, graph, 151, "netns-mc-" + std::to_string(getpid()), 20, {});
  for (auto& p : procs) EXPECT_EQ(p.exit_code, 0) << p.output();
  std::ifstream merged(dir + "/netns-mc-" + std::to_string(getpid()) + ".g2o");
  int lines = 0;
  for (std::string l; std::getline(merged, l);) ++lines;
  EXPECT_EQ(lines, 36);
}

TEST(DdsNetns, MulticastBlockedNeedsAndWorksWithInitialPeers) {
  std::string why;
  if (!namespaces_available(&why))
    GTEST_SKIP() << "network namespaces unavailable here, skipping: " << why;
  Hosts hosts(true);
  ASSERT_TRUE(hosts.ok()) << hosts.error();
  const std::string dir = temp_dir();
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(6, 8));
  // Without peers nobody finds anybody: the coordinator times out naming every agent.
  auto lonely =
      run_across_hosts(hosts, dir, graph, 152, "netns-nopeers-" + std::to_string(getpid()), 2, {});
  EXPECT_EQ(lonely[0].exit_code, 1);
  EXPECT_NE(lonely[0].output().find("missing agent 0, 1, 2"), std::string::npos)
      << lonely[0].output();
  // With the initial-peers list it works.
  auto procs = run_across_hosts(hosts, dir, graph, 153, "netns-peers-" + std::to_string(getpid()),
                                20, {"--peers", hosts.addresses()});
  for (auto& p : procs) EXPECT_EQ(p.exit_code, 0) << p.output();
}

TEST(DdsNetns, MulticastBlockedWorksWithTheDiscoveryServer) {
  std::string why;
  if (!namespaces_available(&why))
    GTEST_SKIP() << "network namespaces unavailable here, skipping: " << why;
  if (access("/usr/bin/fast-discovery-server", X_OK) != 0)
    GTEST_SKIP() << "fast-discovery-server (fastdds-tools) is not installed, skipping";
  Hosts hosts(true);
  ASSERT_TRUE(hosts.ok()) << hosts.error();
  const std::string dir = temp_dir();
  const std::string graph = write_file(dir, "g.g2o", grid_graph_g2o(6, 9));
  // The server itself (not the `fastdds discovery` wrapper, which would outlive a kill).
  Process server = start(hosts.in(0, {"/usr/bin/fast-discovery-server", "-i", "0", "-l",
                                      hosts.address(0), "-p", "11811"}),
                         dir + "/server.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  auto procs = run_across_hosts(hosts, dir, graph, 154, "netns-ds-" + std::to_string(getpid()), 20,
                                {}, "ROS_DISCOVERY_SERVER=" + hosts.address(0) + ":11811");
  for (auto& p : procs) EXPECT_EQ(p.exit_code, 0) << p.output();
  kill(server.pid, SIGINT);  // it ignores SIGTERM
  EXPECT_TRUE(wait_all({&server}, 5)) << server.output();
  run_command("fastdds shm clean", nullptr);
}

}  // namespace
