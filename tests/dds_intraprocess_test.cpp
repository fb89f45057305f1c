// Sessions of one process close however their liveliness assertions fall. Fast DDS 2.9's
// participants of one process used to hand each other their built-in messages inside the
// process, each holding its own participant's mutex while taking the other's: when two writer
// liveliness assertions coincided both event threads deadlocked, and deleting a participant
// then waited for its event thread until the teardown guard ended the process after 5 s
// (transport/fastdds/intraprocess_builtin.hpp). A coordinator and three agents in one process,
// with a 0.2 s lease (an assertion every 50 ms each), deadlocked in 10 of 10 runs before the fix.
// Run in a child process, so a deadlock ends in the guard's exit code 1, not a hung test.
// DDS domain 157 (its own, so ctest -j is safe).

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>
#include <vector>

#include "dds_session_support.hpp"
#include "transport/agent_session.hpp"
#include "transport/coordinator_session.hpp"

namespace tessera::transport {
namespace {

constexpr int kDomain = 157;
constexpr std::uint32_t kAgents = 3;

SessionOptions options_for(bool coordinator, std::uint32_t agent) {
  // The shortest lease allowed: each writer asserts its liveliness every 50 ms.
  SessionOptions o =
      test::session_options("intraprocess-test", kDomain, coordinator, agent, kAgents, 0.2);
  o.transport = "udp";
  return o;
}

// Exit codes of the child: 0 all sessions closed, 1 the teardown guard ended a deadlocked
// deletion, 3 the sessions never matched (the test would prove nothing).
void hold_sessions_together_then_close() {
  auto coordinator = std::make_unique<CoordinatorSession>(options_for(true, 0));
  std::vector<std::unique_ptr<AgentSession>> agents;
  for (std::uint32_t k = 0; k < kAgents; ++k)
    agents.push_back(std::make_unique<AgentSession>(options_for(false, k)));
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!coordinator->endpoints_matched()) {
    if (std::chrono::steady_clock::now() > give_up) {
      std::fprintf(stderr, "the sessions never matched\n");
      std::_Exit(3);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // About 60 assertions per participant while all four are matched.
  std::this_thread::sleep_for(std::chrono::seconds(3));
  agents.clear();
  coordinator.reset();
  std::_Exit(0);
}

TEST(DdsIntraprocess, SessionsOfOneProcessAssertingLivelinessTogetherStillClose) {
  EXPECT_EXIT(hold_sessions_together_then_close(), testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace tessera::transport
