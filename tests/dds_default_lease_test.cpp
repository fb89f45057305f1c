// The participant lease a batch run gets when nobody passes --lease: 2 s (SessionOptions). On a
// loaded 2-core host a live process can go unscheduled for over a second, and a 1 s lease then
// counted live agents lost (docs/dds-runtime.md, "QoS (and why)"); a killed one is still
// noticed, through the 2 s lease, and named. Domain used here: 189.

#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <string>
#include <tessera/dds/session.hpp>

#include "dds_process_support.hpp"
#include "transport/session_options.hpp"

namespace tessera::test::dds {
namespace {

TEST(DdsDefaultLease, BatchProcessesAndThePublicApiDefaultToTwoSeconds) {
  EXPECT_EQ(transport::SessionOptions{}.lease_s, 2.0);
  EXPECT_EQ(tessera::dds::SessionOptions{}.lease_s, 2.0);
}

TEST(DdsDefaultLease, KilledAgentIsLostThroughTheDefaultLeaseAndNamed) {
  const std::string dir = temp_dir();
  const std::string run_id = "deflease-" + std::to_string(getpid());
  struct Cleanup {
    std::string run_id;
    ~Cleanup() { run_command("pkill -9 -f '[t]essera-.*--run-id " + run_id + "'", nullptr); }
  } const cleanup{run_id};
  // 2000 poses and a tolerance the rounds never reach: the run is still in its rounds when
  // agent 1 is killed. No --lease: every process keeps its default.
  Process launch = start(
      {bin("tessera"), "launch",   "--agents",    "3",      "--poses",   "2000",       "--domain",
       "189",          "--run-id", run_id,        "--init", "file",      "--grad-tol", "1e-12",
       "--max-rounds", "100000",   "--partition", "fast",   "--timeout", "60"},
      dir + "/launch.log");
  ASSERT_TRUE(wait_for_round(launch, 2, 30)) << launch.output();
  const pid_t pid = agent_pid(run_id, 1);
  ASSERT_GT(pid, 0);
  kill(pid, SIGKILL);
  ASSERT_TRUE(wait_all({&launch}, 30)) << launch.output();
  EXPECT_EQ(launch.exit_code, 1) << launch.output();
  const std::string out = launch.output();
  EXPECT_NE(out.find("error: lost agent 1"), std::string::npos) << out;
  EXPECT_NE(out.find("(participant lease of 2.0 s expired)"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera::test::dds
