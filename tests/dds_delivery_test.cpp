// Who receives what (docs/dds-runtime.md, "Who receives what"): a pose block addressed to
// one agent reaches only that agent's process, a broadcast reaches every other agent, only
// the round statuses the coordinator reads (coordinator_reads_status) reach the coordinator
// (the solve's only while it follows the rounds; otherwise the agents' progress digests), and
// round statuses go through the relay agent (one bundle per step). A coordinator and three
// agents, each a session of its own in this process, on DDS domain 60.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "dds_session_support.hpp"
#include "transport/agent_session.hpp"
#include "transport/coordinator_session.hpp"
#include "transport/topic_names.hpp"
#include "transport/transport_error.hpp"

namespace {

using namespace tessera;
using namespace tessera::transport;
using tessera::transport::test::pass_readiness_barriers;
using tessera::transport::test::pose_block_to;
using tessera::transport::test::received_phases;
using tessera::transport::test::session_options;

constexpr int kDomain = 60;
constexpr std::uint32_t kAgents = 3;

SessionOptions options_for(bool coordinator, std::uint32_t agent) {
  return session_options("delivery-test", kDomain, coordinator, agent, kAgents, 3.0);
}

OutgoingMessage block_to(std::vector<std::uint32_t> recipients, std::uint32_t phase) {
  return pose_block_to(std::move(recipients), phase, {3}, {1.0, 2.0, 3.0, 4.0});
}

OutgoingMessage status(std::uint32_t phase, std::uint32_t sender = 0, std::uint32_t round = 7) {
  RoundStatusMessage s;
  s.round = round;
  s.sender = sender;
  s.phase = phase;
  s.cost = 1.5;
  OutgoingMessage m;
  m.message = s;
  return m;
}

// Opens a session of role S on `o`, kept in `sessions` (closed in reverse order at the end).
template <class S>
S& open_session(std::vector<std::unique_ptr<Session>>& sessions, const SessionOptions& o) {
  auto owned = std::make_unique<S>(o);
  S& session = *owned;
  sessions.push_back(std::move(owned));
  return session;
}

// The session's type is its role: options of the other role are refused before any
// participant exists.
TEST(DdsDelivery, ASessionRefusesTheOptionsOfTheOtherRole) {
  EXPECT_THROW(AgentSession{options_for(true, 0)}, TransportError);
  EXPECT_THROW(CoordinatorSession{options_for(false, 1)}, TransportError);
}

TEST(DdsDelivery, AddressedBlocksReachOnlyTheirRecipientAndTheCoordinatorOnlyItsStatuses) {
  ASSERT_TRUE(coordinator_reads_status(1, true));
  ASSERT_FALSE(coordinator_reads_status(1, false));   // the digests tell the coordinator
  ASSERT_FALSE(coordinator_reads_status(200, true));  // agent 0's reports: kReportTopic
  ASSERT_FALSE(coordinator_reads_status(101, true));  // a rounding reduction
  ASSERT_FALSE(coordinator_reads_status(300, true));  // the initialisation stage

  std::vector<std::unique_ptr<Session>> sessions;
  CoordinatorSession& coordinator =
      open_session<CoordinatorSession>(sessions, options_for(true, 0));
  AgentSession& a0 = open_session<AgentSession>(sessions, options_for(false, 0));
  AgentSession& a1 = open_session<AgentSession>(sessions, options_for(false, 1));
  AgentSession& a2 = open_session<AgentSession>(sessions, options_for(false, 2));

  // Every process passes the readiness barrier (every endpoint matched, READY from all).
  ASSERT_NO_FATAL_FAILURE(pass_readiness_barriers(sessions, Seconds(30)));

  a0.send(block_to({1}, 2));  // addressed to agent 1 only
  a0.send(block_to({}, 3));   // broadcast
  a0.send(block_to({2}, 4));  // addressed to agent 2 only
  a0.send(status(101));       // a rounding reduction: agents only, all to all
  // Round statuses of the solve go through the relay, agent 0 (transport/status_relay.hpp),
  // when the agents turn it on (as tessera-agent does unless lost agents are arbitrated):
  // agents 1 and 2 send theirs to it alone ... (the coordinator follows the rounds here, as
  // while it arbitrates lost agents)
  RoundTraffic traffic;
  traffic.status_relay = true;
  traffic.coordinator_follows_rounds = true;
  for (AgentSession* a : {&a0, &a1, &a2}) a->set_round_traffic(traffic);
  a1.send(status(1, 1));
  a2.send(status(1, 2));
  const std::vector<std::uint32_t> at0 = received_phases(a0, 2);
  EXPECT_EQ(at0, (std::vector<std::uint32_t>{1u, 1u}));
  // ... and its own completes the step: one bundle of all three to every agent and the
  // coordinator.
  a0.send(status(1, 0));
  a0.flush(Seconds(10));  // acknowledged = delivered to every matched reader

  const std::vector<std::uint32_t> at1 = received_phases(a1, 5);
  const std::vector<std::uint32_t> at2 = received_phases(a2, 5);
  EXPECT_EQ(at1.size(), 5u);
  EXPECT_EQ(at2.size(), 5u);
  EXPECT_EQ(std::count(at1.begin(), at1.end(), 2u), 1);
  EXPECT_EQ(std::count(at1.begin(), at1.end(), 4u), 0);
  EXPECT_EQ(std::count(at2.begin(), at2.end(), 4u), 1);
  EXPECT_EQ(std::count(at2.begin(), at2.end(), 2u), 0);
  for (const auto* at : {&at1, &at2}) {
    for (std::uint32_t phase : {3u, 101u}) EXPECT_EQ(std::count(at->begin(), at->end(), phase), 1);
    EXPECT_EQ(std::count(at->begin(), at->end(), 1u), 2);  // the other two agents' statuses
  }
  // Nothing more was delivered to either agent's process: the addressed block of the other
  // agent never reached it, not even to be dropped, and the two statuses came as one sample.
  EXPECT_EQ(a1.stats().protocol_samples_received, 4u);
  EXPECT_EQ(a2.stats().protocol_samples_received, 4u);
  // The sender's own readers see its broadcasts and its bundle (same topic, same
  // participant) but never pass them on.
  EXPECT_EQ(a0.protocol().size(), 0u);

  // The coordinator got the round statuses only, every agent's, from the one bundle.
  std::vector<wire::RoundStatus> watched;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < until) {
    for (auto& m : coordinator.status_watch().take_all()) watched.push_back(std::move(m));
    if (!watched.empty()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // room for a wrong extra one
  for (auto& m : coordinator.status_watch().take_all()) watched.push_back(std::move(m));
  ASSERT_EQ(watched.size(), 3u);
  for (std::uint32_t k = 0; k < 3; ++k) {
    EXPECT_EQ(watched[k].phase(), 1u);
    EXPECT_EQ(watched[k].sender(), k);
    EXPECT_EQ(watched[k].round(), 7u);
  }

  // By default the coordinator follows the agents' progress digests: the statuses of the
  // solve and their bundle stay among the agents; the coordinator gets the digest and agent
  // 0's report, nothing else.
  traffic.coordinator_follows_rounds = false;
  for (AgentSession* a : {&a0, &a1, &a2}) a->set_round_traffic(traffic);
  a1.send(status(1, 1, 8));
  a2.send(status(1, 2, 8));
  EXPECT_EQ(received_phases(a0, 2), (std::vector<std::uint32_t>{1u, 1u}));
  a0.send(status(1, 0, 8));
  wire::AgentProgress digest;
  digest.sender(1);
  digest.round(8);
  digest.phase(1);
  digest.cost(4.5);
  a1.publish(digest);
  a0.report(agent::FinalReport{2.5, 1e-3, 1});  // agent 0's final report: its own topic
  for (AgentSession* a : {&a0, &a1, &a2}) a->flush(Seconds(10));
  for (AgentSession* a : {&a1, &a2}) {
    const std::vector<std::uint32_t> at = received_phases(*a, 2);
    EXPECT_EQ(std::count(at.begin(), at.end(), 1u), 2);
  }
  std::vector<wire::AgentProgress> digests;
  const auto digest_until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (digests.empty() && std::chrono::steady_clock::now() < digest_until) {
    for (auto& m : coordinator.progress().take_all()) digests.push_back(std::move(m));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // room for a wrong extra one
  for (auto& m : coordinator.progress().take_all()) digests.push_back(std::move(m));
  ASSERT_EQ(digests.size(), 1u);
  EXPECT_EQ(digests[0].sender(), 1u);
  EXPECT_EQ(digests[0].round(), 8u);
  EXPECT_EQ(digests[0].cost(), 4.5);
  EXPECT_EQ(digests[0].run_id(), "delivery-test");
  EXPECT_TRUE(coordinator.status_watch().take_all().empty());
  const std::vector<wire::AgentReport> reports = coordinator.reports().take_all();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].sender(), 0u);
  ASSERT_EQ(reports[0].body()._d(), wire::REPORT_FINAL);
  EXPECT_EQ(reports[0].body().final_report().cost(), 2.5);
  // And no agent received it, not even to drop it.
  EXPECT_EQ(a1.protocol().size(), 0u);
  EXPECT_EQ(a2.protocol().size(), 0u);

  for (auto it = sessions.rbegin(); it != sessions.rend(); ++it) (*it)->close();
}

// Blocks to the relay ride in the sender's relayed status (AgentSession::send_all,
// transport/riding_blocks.hpp): one sample reaches the relay for both, the block's other
// recipients get it as before, and a step without a relayed status sends its blocks alone.
TEST(DdsDelivery, BlocksToTheRelayRideInTheSendersStatusSample) {
  constexpr int kRidingDomain = 226;
  auto riding = [](bool coordinator, std::uint32_t agent) {
    SessionOptions o = options_for(coordinator, agent);
    o.run_id = "riding-test";
    o.domain = kRidingDomain;
    return o;
  };
  std::vector<std::unique_ptr<Session>> sessions;
  open_session<CoordinatorSession>(sessions, riding(true, 0));
  AgentSession& a0 = open_session<AgentSession>(sessions, riding(false, 0));
  AgentSession& a1 = open_session<AgentSession>(sessions, riding(false, 1));
  AgentSession& a2 = open_session<AgentSession>(sessions, riding(false, 2));
  ASSERT_NO_FATAL_FAILURE(pass_readiness_barriers(sessions, Seconds(30)));
  RoundTraffic traffic;
  traffic.status_relay = true;
  for (AgentSession* a : {&a0, &a1, &a2}) a->set_round_traffic(traffic);

  auto block_from_1 = [](std::vector<std::uint32_t> to, std::uint32_t pose) {
    OutgoingMessage m = block_to(std::move(to), 3);  // an update step's Y poses
    std::get<PoseBlockMessage>(m.message).sender = 1;
    std::get<PoseBlockMessage>(m.message).pose_ids = {pose};
    return m;
  };
  // Agent 1's step: its new poses for agents 0 (the relay) and 2, then its status.
  a1.send_all({block_from_1({0}, 10), block_from_1({2}, 11), status(1, 1)});
  a1.flush(Seconds(10));
  std::vector<ProtocolMessage> at0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (at0.size() < 2 && std::chrono::steady_clock::now() < until) {
    ProtocolMessage m;
    if (a0.protocol().take(Seconds(0.2), &m) == WaitStatus::kReady) at0.push_back(std::move(m));
  }
  ASSERT_EQ(at0.size(), 2u);
  const auto* block = std::get_if<PoseBlockMessage>(&at0[0]);  // the riding block comes first
  ASSERT_NE(block, nullptr);
  EXPECT_EQ(block->sender, 1u);
  EXPECT_EQ(block->phase, 3u);
  EXPECT_EQ(block->pose_ids, (std::vector<std::uint32_t>{10}));
  EXPECT_EQ(block->data, (std::vector<double>{1.0, 2.0, 3.0, 4.0}));
  const auto* st = std::get_if<RoundStatusMessage>(&at0[1]);
  ASSERT_NE(st, nullptr);
  EXPECT_EQ(st->sender, 1u);
  EXPECT_EQ(st->phase, 1u);
  EXPECT_EQ(a0.stats().protocol_samples_received, 1u);  // both in one sample
  const std::vector<std::uint32_t> at2 = received_phases(a2, 1);
  EXPECT_EQ(at2, (std::vector<std::uint32_t>{3u}));
  EXPECT_EQ(a2.stats().protocol_samples_received, 1u);

  // The relay kept the status (without the block): with agent 2's and its own the step
  // completes, and agent 1 gets the bundle of the other two.
  a2.send_all({status(1, 2)});
  EXPECT_EQ(received_phases(a0, 1), (std::vector<std::uint32_t>{1u}));
  a0.send_all({status(1, 0)});
  EXPECT_EQ(received_phases(a1, 2), (std::vector<std::uint32_t>{1u, 1u}));

  // A step whose status is not relayed (a rounding reduction): the block travels alone.
  a1.send_all({block_from_1({0}, 12), status(101, 1)});
  EXPECT_EQ(received_phases(a0, 2).size(), 2u);
  // 1 + agent 2's status + its own bundle (seen by its own reader, dropped) + these 2
  EXPECT_EQ(a0.stats().protocol_samples_received, 5u);
  EXPECT_EQ(a0.protocol().size(), 0u);

  for (auto it = sessions.rbegin(); it != sessions.rend(); ++it) (*it)->close();
}

}  // namespace
