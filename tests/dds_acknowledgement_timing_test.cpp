// When readers acknowledge, as set by transport/qos.cpp. A reader acknowledges only when a
// heartbeat asks, or once, a delay after it matched a writer:
// - the hand-off writers (writer_qos's `waited_for`): an agent waits for its hand-off parts to
//   be acknowledged every few parts (agent/handoff_exchange.cpp), so each wait lasted until the
//   writer's next heartbeat, 50 ms at the per-round topics' period, or, for a lost part, until
//   the end of the writer's 50 ms NACK suppression window;
// - the hand-shake readers (TRANSIENT_LOCAL): a sample dropped because it arrived before its
//   writer was matched came again only at the reader's first acknowledgement, 70 ms by default.
// No timing is asserted, only the QoS each endpoint gets.

#include <gtest/gtest.h>

#include "transport/network_profile.hpp"
#include "transport/qos.hpp"
#include "transport/topic_names.hpp"

namespace {

using namespace tessera::transport;

double seconds(const eprosima::fastrtps::Duration_t& d) {
  return static_cast<double>(d.to_ns()) * 1e-9;
}
double heartbeat_s(const eprosima::fastdds::dds::DataWriterQos& q) {
  return seconds(q.reliable_writer_qos().times.heartbeatPeriod);
}
double nack_window_s(const eprosima::fastdds::dds::DataWriterQos& q) {
  return seconds(q.reliable_writer_qos().times.nackSupressionDuration);
}
double first_acknack_s(const eprosima::fastdds::dds::DataReaderQos& q) {
  return seconds(q.reliable_reader_qos().times.initialAcknackDelay);
}

TEST(HandoffHeartbeat, HandoffWritersOfSmallRunsAskForAcknowledgementsAndRepairAtTheHandshakePace) {
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
  // A part lost in the burst is repaired at once, not after the NACK suppression window.
  EXPECT_EQ(nack_window_s(writer_qos(false, 2.0, 5, def, true, waited_for)), 0.0);
  // Every other volatile writer keeps the profile's period and window.
  EXPECT_NEAR(nack_window_s(writer_qos(false, 2.0, 5, def, true)), def.nack_suppression_s, 1e-9);
  EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, 5, def, false)), def.heartbeat_period_s, 1e-9);
  EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, 5, def, true)), def.heartbeat_period_s, 1e-9);
}

TEST(HandoffHeartbeat, LargerRunsKeepTheProfilesPeriodSinceEachHeartbeatAsksEveryReader) {
  const NetworkProfile def = network_profile("default");
  for (std::uint32_t agents : {kMaxAgentsWithRecipientTopics + 1, 25u, 64u})
    EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, agents, def, true, true)),
                def.heartbeat_period_s, 1e-9)
        << agents << " agents";
  EXPECT_NEAR(nack_window_s(writer_qos(false, 2.0, 25, def, true, true)), def.nack_suppression_s,
              1e-9);
  // A profile with a shorter period than the hand-shake's keeps its own.
  NetworkProfile fast = def;
  fast.heartbeat_period_s = 0.001;
  EXPECT_NEAR(heartbeat_s(writer_qos(false, 2.0, 5, fast, true, true)), 0.001, 1e-9);
}

TEST(HandshakeReaders, AskForWhatTheyMissedAHandshakeHeartbeatAfterMatchingNot70Ms) {
  const NetworkProfile def = network_profile("default");
  const eprosima::fastdds::dds::DataReaderQos fast_dds_default;
  ASSERT_NEAR(first_acknack_s(fast_dds_default), 0.070, 1e-9);
  for (std::uint32_t agents : {2u, 5u, 64u})
    EXPECT_NEAR(first_acknack_s(reader_qos(true, 2.0, agents, def, true)), kHandshakeHeartbeatS,
                1e-9)
        << agents << " agents";
  // The volatile readers get only what is written after they matched: Fast DDS's delay.
  EXPECT_NEAR(first_acknack_s(reader_qos(false, 2.0, 5, def, false)), 0.070, 1e-9);
}

}  // namespace
