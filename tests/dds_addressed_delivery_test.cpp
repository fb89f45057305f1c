// Addressed delivery in runs of more than 8 agents (transport/addressed_filter.hpp): the content
// filter reads the recipient off a serialized hand-off or pose block without decoding it, and
// over DDS an addressed block reaches only its recipient's process (the others' filtered readers
// never take it), a block too large for one transport message still arrives (on the shared
// topic), and hand-offs in parts reach their recipient whole. A coordinator and ten agents,
// each a session of its own in this process, on DDS domain 95.

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "agent/handoff_exchange.hpp"
#include "dds_session_support.hpp"
#include "tesseraPubSubTypes.h"
#include "transport/addressed_filter.hpp"
#include "transport/agent_session.hpp"
#include "transport/coordinator_session.hpp"
#include "transport/message_mapping.hpp"
#include "transport/topic_names.hpp"

namespace {

using namespace tessera;
using namespace tessera::transport;
using tessera::transport::test::pass_readiness_barriers;
using tessera::transport::test::pose_block_to;
using tessera::transport::test::received_phases;
using tessera::transport::test::session_options;

constexpr int kDomain = 95;
constexpr std::uint32_t kAgents = kMaxAgentsWithRecipientTopics + 2;

// The CDR bytes DDS would send for `sample`.
template <class PubSubType, class T>
std::vector<std::uint8_t> serialized(T sample) {
  PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(
      static_cast<std::uint32_t>(serialized_size(sample) + 64));
  EXPECT_TRUE(type.serialize(&sample, &payload));
  return std::vector<std::uint8_t>(payload.data, payload.data + payload.length);
}

wire::MeasurementHandoff handoff(std::uint32_t sender, std::uint32_t recipient,
                                 const std::string& run_id) {
  wire::MeasurementHandoff h;
  h.run_id(run_id);
  h.sender(sender);
  h.recipient(recipient);
  h.meas_i({1, 2, 3});
  return h;
}

wire::PoseBlock block(bool broadcast, std::vector<std::uint32_t> recipients,
                      const std::string& run_id) {
  wire::PoseBlock b;
  b.run_id(run_id);
  b.round(3);
  b.sender(1);
  b.broadcast(broadcast);
  b.recipients(std::move(recipients));
  b.pose_ids({7, 8});
  b.data(std::vector<double>(24, 0.5));
  return b;
}

TEST(AddressedFilter, PassesAHandoffToItsRecipientOnly) {
  // Run ids of every length mod 4: the recipient field follows the string's padding.
  for (const std::string run : {"r", "ru", "run", "run1", "launch-1234-56789"}) {
    const auto bytes = serialized<wire::MeasurementHandoffPubSubType>(handoff(2, 5, run));
    for (std::uint32_t agent = 0; agent < 8; ++agent)
      EXPECT_EQ(addressed_to_agent(AddressedLayout::kHandoff, bytes.data(), bytes.size(), agent),
                agent == 5)
          << run << " agent " << agent;
  }
}

TEST(AddressedFilter, PassesABlockToItsRecipientsOrToEveryoneWhenBroadcast) {
  for (const std::string run : {"r", "ru", "run", "run1"}) {
    const auto to_3_and_9 = serialized<wire::PoseBlockPubSubType>(block(false, {3, 9}, run));
    const auto to_all = serialized<wire::PoseBlockPubSubType>(block(true, {}, run));
    for (std::uint32_t agent = 0; agent < 12; ++agent) {
      EXPECT_EQ(
          addressed_to_agent(AddressedLayout::kBlock, to_3_and_9.data(), to_3_and_9.size(), agent),
          agent == 3 || agent == 9)
          << run << " agent " << agent;
      EXPECT_TRUE(addressed_to_agent(AddressedLayout::kBlock, to_all.data(), to_all.size(), agent));
    }
  }
}

TEST(AddressedFilter, PassesWhatItCannotReadSoThatTheReaderReportsIt) {
  const auto bytes = serialized<wire::PoseBlockPubSubType>(block(false, {3}, "run"));
  // Cut inside the recipient (header 4, "run" 8, round, sender, phase 12, broadcast 1 and
  // padding 3, count 4: the recipient starts at byte 32): the filter cannot tell, the reader's
  // decoding will.
  ASSERT_FALSE(addressed_to_agent(AddressedLayout::kBlock, bytes.data(), bytes.size(), 4));
  EXPECT_TRUE(addressed_to_agent(AddressedLayout::kBlock, bytes.data(), 34, 4));
  EXPECT_TRUE(addressed_to_agent(AddressedLayout::kHandoff, bytes.data(), 2, 4));
  EXPECT_TRUE(addressed_to_agent(AddressedLayout::kHandoff, nullptr, 0, 4));
}

SessionOptions options_for(bool coordinator, std::uint32_t agent) {
  return session_options("addressed-test", kDomain, coordinator, agent, kAgents, 5.0);
}

// A block of `poses` poses to `recipients` (not empty).
OutgoingMessage block_to(std::vector<std::uint32_t> recipients, std::uint32_t phase,
                         std::size_t poses) {
  std::vector<std::uint32_t> ids(poses);
  std::iota(ids.begin(), ids.end(), 0u);
  return pose_block_to(std::move(recipients), phase, std::move(ids),
                       std::vector<double>(poses * 4, 1.0));
}

TEST(DdsAddressedDelivery, BlocksAndHandoffsReachOnlyTheirRecipientInALargeRun) {
  std::vector<std::unique_ptr<Session>> sessions;
  sessions.push_back(std::make_unique<CoordinatorSession>(options_for(true, 0)));
  std::vector<AgentSession*> agents;
  for (std::uint32_t k = 0; k < kAgents; ++k) {
    auto a = std::make_unique<AgentSession>(options_for(false, k));
    agents.push_back(a.get());
    sessions.push_back(std::move(a));
  }
  ASSERT_NO_FATAL_FAILURE(pass_readiness_barriers(sessions, Seconds(60)));

  // A small block to agent 1 (filtered topic), a large one to agent 2 (over one transport
  // message: the shared topic, dropped by every other agent's router).
  agents[0]->send(block_to({1}, 2, 4));
  agents[0]->send(block_to({2}, 3, 4000));
  agents[0]->flush(Seconds(20));
  EXPECT_EQ(received_phases(*agents[1], 1), (std::vector<std::uint32_t>{2u}));
  EXPECT_EQ(received_phases(*agents[2], 1), (std::vector<std::uint32_t>{3u}));
  EXPECT_EQ(agents[1]->stats().protocol_samples_received, 2u) << "its own and the large one";
  for (std::uint32_t k = 3; k < kAgents; ++k)
    EXPECT_EQ(agents[k]->stats().protocol_samples_received, 1u)
        << "agent " << k << " took only the large block of the shared topic";

  // Hand-offs in parts: agent 3's share has 2000 measurements touching agent 4's poses (more
  // than one part) and 600 of its initial poses now owned by agent 4; the others get none.
  agent::RobotShare share;
  share.d = 2;
  share.num_poses = 4000;
  share.begin = 0;
  share.end = 2000;
  std::vector<std::uint32_t> owner(4000, 3);
  for (std::uint32_t i = 1400; i < 2000; ++i) owner[i] = 4;
  for (std::uint32_t i = 2000; i < 4000; ++i) owner[i] = 4;
  for (std::size_t k = 0; k < 2000; ++k) {
    Measurement m;
    m.i = k;
    m.j = 2000 + k;
    m.R = Eigen::MatrixXd::Identity(2, 2);
    m.t = Eigen::VectorXd::Constant(2, static_cast<double>(k));
    m.kappa = 1.0;
    m.tau = 2.0;
    share.measurements.push_back(m);
    share.measurement_index.push_back(k);
  }
  for (std::size_t k = 0; k < 2000; ++k) {
    Pose p = Pose::identity(2);
    p.t << static_cast<double>(k), 0.0;
    share.initial.push_back(p);
  }
  auto sent = std::async(std::launch::async, [&] {
    agent::RobotShare none;
    none.d = 2;
    none.num_poses = 4000;
    // Every agent's exchange needs one hand-off from each of the others: the others send
    // empty ones, agent 3 the real one.
    std::vector<std::future<std::vector<agent::ReceivedHandoff>>> all;
    for (std::uint32_t k = 0; k < kAgents; ++k)
      all.push_back(std::async(std::launch::async, [&, k] {
        return agent::exchange_handoffs(*agents[k], k == 3 ? share : none, owner, k, kAgents,
                                        "addressed-test", 60.0);
      }));
    std::vector<std::vector<agent::ReceivedHandoff>> got;
    for (auto& f : all) got.push_back(f.get());
    return got;
  });
  const auto got = sent.get();
  for (std::uint32_t k = 0; k < kAgents; ++k) {
    ASSERT_EQ(got[k].size(), kAgents - 1) << "agent " << k;
    for (const auto& h : got[k]) {
      if (k == 4 && h.sender == 3) {
        ASSERT_EQ(h.measurements.size(), 2000u);
        ASSERT_EQ(h.poses.size(), 600u);
        for (std::size_t e = 0; e < 2000; ++e) {
          EXPECT_EQ(h.measurement_index[e], e) << "the sender's order, across parts";
          EXPECT_EQ(h.measurements[e].t(0), static_cast<double>(e));
        }
        EXPECT_EQ(h.poses.front().first, 1400u);
        EXPECT_EQ(h.poses.back().first, 1999u);
      } else {
        EXPECT_TRUE(h.measurements.empty() && h.poses.empty())
            << "agent " << k << " from " << h.sender;
      }
    }
  }
}

}  // namespace
