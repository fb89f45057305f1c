// An agent that aborts at the end of a run (issue #5: Fast DDS 2.9's lease-check assertion
// while the other participants leave, seen once in agent 0 in ~100 launches). Once the
// coordinator's FINISHED has arrived the run is complete, and such an abort must end the agent
// with exit code 0 and a note (cli/session_process.cpp, transport/fastdds/teardown_guard.hpp), so
// that launch reports the finished run as finished; before its result is delivered an abort must
// still fail the run. The abort is raised by the test-only TESSERA_TEST_AGENT_ABORT
// (agent/test_abort_hook.hpp), given through /usr/bin/env.
// Domains used here: 106-108 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <utility>
#include <vector>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

const char* const kNote = "note: Fast DDS aborted after the run's work was done";

// argv run with TESSERA_TEST_AGENT_ABORT=spec in its environment.
std::vector<std::string> with_abort(const std::string& spec, std::vector<std::string> argv) {
  return with_env("TESSERA_TEST_AGENT_ABORT=" + spec, std::move(argv));
}

std::vector<std::string> launch_args(const std::string& graph, int domain, const std::string& run) {
  return {bin("tessera"),         "launch",   graph, "--agents",  "2", "--no-certify", "--domain",
          std::to_string(domain), "--run-id", run,   "--timeout", "60"};
}

struct Cleanup {
  std::string run_id;
  ~Cleanup() { run_command("pkill -9 -f '[t]essera-.*--run-id " + run_id + " '", nullptr); }
};

TEST(DdsAgentEndAbort, AnAbortAfterFinishedEndsTheAgentWithExitZeroAndANote) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 200 --robots 2 --seed 3");
  const int domain = 106;
  const Cleanup cleanup{"endabort-" + std::to_string(getpid())};
  const std::string& run = cleanup.run_id;
  const auto before = shm_files();
  Process coord =
      start(coordinator_args(2, run, domain, {"--timeout", "30"}), dir + "/coordinator.log");
  Process a0 = start(
      with_abort("after-finished:0", agent_args(graph, 2, 0, run, domain, {"--timeout", "30"})),
      dir + "/agent0.log");
  Process a1 =
      start(agent_args(graph, 2, 1, run, domain, {"--timeout", "30"}), dir + "/agent1.log");
  ASSERT_TRUE(wait_all({&coord, &a0, &a1}, 60)) << "a process hung";
  const std::string out0 = a0.output();
  EXPECT_NE(out0.find("aborting after-finished"), std::string::npos) << out0;  // it did abort
  EXPECT_NE(out0.find(kNote), std::string::npos) << out0;
  EXPECT_NE(out0.find("exiting with code 0 as intended"), std::string::npos) << out0;
  EXPECT_EQ(a0.exit_code, 0) << out0;
  EXPECT_EQ(a1.exit_code, 0) << a1.output();
  EXPECT_EQ(coord.exit_code, 0) << coord.output();
  remove_shm_files(leaked_shm_files(before, domain));  // the aborted agent's (no launch here)
}

TEST(DdsAgentEndAbort, LaunchReportsARunWhoseAgentAbortsAfterFinishedAsFinished) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 200 --robots 2 --seed 3");
  const Cleanup cleanup{"endabort2-" + std::to_string(getpid())};
  std::vector<std::string> argv = launch_args(graph, 107, cleanup.run_id);
  argv.insert(argv.end(), {"--json", dir + "/summary.json"});
  const auto before = shm_files();
  Process launch = start(with_abort("after-finished:0", argv), dir + "/launch.log");
  ASSERT_TRUE(wait_all({&launch}, 90)) << launch.output();
  const std::string out = launch.output();
  EXPECT_EQ(launch.exit_code, 0) << out;
  EXPECT_EQ(out.find("failed"), std::string::npos) << out;
  EXPECT_NE(out.find("wall time"), std::string::npos) << out;
  // The agent's log is removed with launch's folder: launch repeats its note.
  EXPECT_NE(out.find(std::string("tessera launch: agent 0: tessera-agent[0]: ") + kNote),
            std::string::npos)
      << out;
  EXPECT_GT(json_field(slurp(dir + "/summary.json"), "rounds"), 0) << out;
  // The aborted agent could not remove its shared-memory files: launch does, as after a
  // failed run (a dead port can keep later runs of the domain from discovering each other).
  expect_launch_removed_dead_shm_files(out, before, 107);
}

TEST(DdsAgentEndAbort, AnAbortBeforeTheResultIsDeliveredStillFailsTheRun) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 200 --robots 2 --seed 3");
  const Cleanup cleanup{"endabort3-" + std::to_string(getpid())};
  Process launch = start(with_abort("before-result:1", launch_args(graph, 108, cleanup.run_id)),
                         dir + "/launch.log");
  ASSERT_TRUE(wait_all({&launch}, 90)) << launch.output();
  const std::string out = launch.output();
  EXPECT_EQ(launch.exit_code, 1) << out;
  EXPECT_NE(out.find("agent 1 failed (exit code 134"), std::string::npos) << out;
  EXPECT_NE(out.find("aborting before-result"), std::string::npos) << out;
  EXPECT_EQ(out.find(kNote), std::string::npos) << out;  // not covered
}

}  // namespace
}  // namespace tessera::test::dds
