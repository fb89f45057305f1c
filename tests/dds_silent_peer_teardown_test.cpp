// A participant's last shared-memory messages must stay readable after it is deleted: Fast DDS
// 2.9.1's listener opens a sender's segment by name when it reads that sender's first message
// (or one after its copy was dropped), and without the segment it retries that message forever
// (transport/fastdds/shm_receive_watch.hpp); the session keeps a deleted participant's segment
// readable (transport/fastdds/shm_segment_keeper.hpp). The other processes are
// tests/silent_peer_main.cpp; DDS domain 101.

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "dds_process_support.hpp"
#include "dds_session_support.hpp"
#include "transport/agent_session.hpp"

namespace tessera::transport {
namespace {

namespace dds = tessera::test::dds;  // process helpers (the agent's own are transport::test)

constexpr int kDomain = 101;

std::string peer_binary() {
  return std::string(TESSERA_BIN_DIR) + "/tessera_test_silent_peer";
}

// The one agent of a one-agent run on this test's domain, over `transport`.
SessionOptions agent_options(const std::string& run, const std::string& transport) {
  SessionOptions o =
      transport::test::session_options(run, kDomain, /*coordinator=*/false, 0, 1, 3.0);
  o.transport = transport;
  return o;
}

// Shared memory only (discovery too, as `tessera launch` runs by default): a process of another
// run on the domain is stopped while this process's participant announces itself and is
// deleted, so it reads that participant's first messages only after the participant is gone.
// Fast DDS 2.9.1 alone: its listener retries the first one forever, 3 runs of 3 (it counts
// 12,000-19,000 receive errors in 1.5 s and exits 4). With the segment kept: it reads it.
TEST(DdsSilentPeer, AProcessThatReadsADeletedParticipantsFirstMessagesLateIsNotStuck) {
  const std::string dir = tessera::test::temp_dir();
  for (int i = 0; i < 3; ++i) {
    dds::Process other =
        dds::start({peer_binary(), "coordinator", "late-reader-" + std::to_string(i),
                    std::to_string(kDomain), "1500000", "shm"},
                   dir + "/other" + std::to_string(i) + ".log");
    ASSERT_TRUE(dds::wait_for_output(other, "coordinator up", 30.0)) << other.output();
    kill(other.pid, SIGSTOP);
    auto leaver =
        std::make_unique<AgentSession>(agent_options("leaver-" + std::to_string(i), "shm"));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // a few announcements
    leaver.reset();
    kill(other.pid, SIGCONT);
    ASSERT_TRUE(dds::wait_all({&other}, 30.0)) << other.output();
    EXPECT_EQ(other.exit_code, 0) << other.output();
  }
}

// The default transport (discovery over UDP, data over shared memory): the coordinator (another
// process) is stopped for 0.3 s from the moment this process's agent has matched it, and the
// agent leaves meanwhile without sending any data of the run (a set-up that fails early). The
// coordinator reads what the agent's endpoints sent at the match only after the stop.
TEST(DdsSilentPeer, ACoordinatorStoppedWhileASilentAgentLeavesReadsOnAfterwards) {
  const std::string dir = tessera::test::temp_dir();
  for (int i = 0; i < 5; ++i) {
    const std::string run = "silent-agent-" + std::to_string(i);
    dds::Process coordinator =
        dds::start({peer_binary(), "coordinator", run, std::to_string(kDomain), "1500000"},
                   dir + "/coordinator" + std::to_string(i) + ".log");
    auto agent = std::make_unique<AgentSession>(agent_options(run, "default"));
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!agent->endpoints_matched() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    ASSERT_TRUE(agent->endpoints_matched());
    kill(coordinator.pid, SIGSTOP);
    std::thread resume([pid = coordinator.pid] {
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      kill(pid, SIGCONT);
    });
    agent.reset();
    resume.join();
    ASSERT_TRUE(dds::wait_all({&coordinator}, 30.0)) << coordinator.output();
    EXPECT_EQ(coordinator.exit_code, 0) << coordinator.output();
  }
}

}  // namespace
}  // namespace tessera::transport
