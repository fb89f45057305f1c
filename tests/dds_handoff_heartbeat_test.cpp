// The heartbeat of the hand-off writers (transport/qos.cpp, writer_qos's `waited_for`). An agent
// waits for its hand-off parts to be acknowledged every few parts (agent/handoff_exchange.cpp),
// and a reader acknowledges only when a heartbeat asks: at the per-round topics' 50 ms each wait
// lasted until the next heartbeat. No timing is asserted, only the QoS each writer gets.

#include <gtest/gtest.h>

#include "transport/network_profile.hpp"
#include "transport/qos.hpp"
#include "transport/topic_names.hpp"

namespace {

using namespace tessera::transport;

double heartbeat_s(const eprosima::fastdds::dds::DataWriterQos& q) {
  return static_cast<double>(q.reliable_writer_qos().times.heartbeatPeriod.to_ns()) * 1e-9;
}

TEST(HandoffHeartbeat, HandoffWritersOfSmallRunsAskForAcknowledgementsAtTheHandshakePeriod) {
  const NetworkProfile def = network_profile("default");
  ASSERT_GT(def.heartbeat_period_s, kHandshakeHeartbeatS);
  EXPECT_TRUE(is_handoff_topic(kHandoffTopic));
  EXPECT_TRUE(is_handoff_topic(kAddressedHandoffTopic));
  EXPECT_FALSE(is_handoff_topic(kBlockTopic));
  EXPECT_FALSE(is_handoff_topic(kStatusTopic));
  const bool waited_for = true;
  for (std::uint32_t agents : {2u, 5u, kMaxAgentsWithRecipientTopics})
    EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, agents, def, true, waited_for)),
                kHandshakeHeartbeatS, 1e-9)
        << agents << " agents";
  // Every other volatile writer keeps the profile's period.
  EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, 5, def, false)), def.heartbeat_period_s, 1e-9);
  EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, 5, def, true)), def.heartbeat_period_s, 1e-9);
}

TEST(HandoffHeartbeat, LargerRunsKeepTheProfilesPeriodSinceEachHeartbeatAsksEveryReader) {
  const NetworkProfile def = network_profile("default");
  for (std::uint32_t agents : {kMaxAgentsWithRecipientTopics + 1, 25u, 64u})
    EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, agents, def, true, true)),
                def.heartbeat_period_s, 1e-9)
        << agents << " agents";
  // A profile with a shorter period than the hand-shake's keeps its own.
  NetworkProfile fast = def;
  fast.heartbeat_period_s = 0.001;
  EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, 5, fast, true, true)), 0.001, 1e-9);
}

}  // namespace
