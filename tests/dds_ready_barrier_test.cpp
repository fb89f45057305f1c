// The readiness barrier's time-out names each peer whose READY did not come with what this
// process knows of it, so a set-up that never reaches the rounds says where it stopped: a peer
// not discovered, one whose READY writer this process never matched, or one matched that sent
// nothing. Sessions of both roles in this process, on DDS domain 132 (its own, so ctest -j is
// safe).

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "dds_session_support.hpp"
#include "transport/agent_session.hpp"
#include "transport/coordinator_session.hpp"

namespace tessera::transport {
namespace {

constexpr int kDomain = 132;

SessionOptions options_for(bool coordinator, std::uint32_t agent) {
  SessionOptions o =
      test::session_options("ready-barrier-test", kDomain, coordinator, agent, 1, 3.0);
  // UDP only: the subject is the barrier's message, not the transport. (This test's teardown
  // overran its 5 s guard in 7 of 126 runs at load 10-16: its two sessions' liveliness
  // assertions deadlocked, transport/fastdds/intraprocess_builtin.hpp.)
  o.transport = "udp";
  return o;
}

// The agent's endpoints match the coordinator's, but it never enters the barrier, so it never
// sends READY: the coordinator's time-out says the agent was there and matched.
TEST(DdsReadyBarrier, ATimeOutSaysWhenThePeerWasMatchedButSentNoReady) {
  auto coordinator = std::make_unique<CoordinatorSession>(options_for(true, 0));
  auto agent = std::make_unique<AgentSession>(options_for(false, 0));
  std::string missing;
  EXPECT_EQ(coordinator->ready_barrier(Seconds(5), &missing), WaitStatus::kTimeout);
  EXPECT_EQ(missing, "no READY from agent 0 (its writer matched, nothing received)");
  agent.reset();
  coordinator.reset();
}

}  // namespace
}  // namespace tessera::transport
