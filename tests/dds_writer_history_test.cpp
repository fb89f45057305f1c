// What a per-round writer keeps (transport/acknowledged_drop.hpp, kDropAcknowledgedEvery): its
// readers are VOLATILE, so once every sample is acknowledged the writer drops them, instead of
// keeping its last kVolatileWriterHistory samples for the rest of the run (its writer is
// TRANSIENT_LOCAL, fastdds/reader_removal_lock_order.hpp). Agent 0 sends large pose blocks to
// agent 1 one at a time, each acknowledged before the next, as rounds do; the process's heap in
// use must not grow with the number sent. A batch run's sessions (a coordinator and two agents,
// each a session of its own in this process) on DDS domain 210; an online mission's channels
// (two agents) on domain 211.

#include <gtest/gtest.h>
#include <malloc.h>

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "dds_session_support.hpp"
#include "transport/agent_session.hpp"
#include "transport/coordinator_session.hpp"
#include "transport/online_channel.hpp"
#include "transport/qos.hpp"
#include "transport/sample_writing.hpp"

namespace {

using namespace tessera;
using namespace tessera::transport;
using tessera::transport::test::pass_readiness_barriers;
using tessera::transport::test::pose_block_to;
using tessera::transport::test::received_phases;
using tessera::transport::test::session_options;

constexpr int kDomain = 210;
constexpr int kOnlineDomain = 211;
constexpr std::uint32_t kAgents = 2;
constexpr std::size_t kPoses = 4000;  // 16,000 values: a 128 KB sample
constexpr std::size_t kMB = 1u << 20;

SessionOptions options_for(bool coordinator, std::uint32_t agent) {
  return session_options("writer-history-test", kDomain, coordinator, agent, kAgents, 3.0);
}

// Heap in use: the arena's chunks and the mmapped ones (a 128 KB payload may be either).
std::size_t heap_in_use() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
}

// Agent 0 sends `count` blocks to agent 1, each received and acknowledged before the next.
void send_one_at_a_time(AgentSession& from, AgentSession& to, int count) {
  std::vector<std::uint32_t> ids(kPoses);
  for (std::size_t i = 0; i < kPoses; ++i) ids[i] = static_cast<std::uint32_t>(i);
  const std::vector<double> data(4 * kPoses, 1.0);
  for (int i = 0; i < count; ++i) {
    from.send(pose_block_to({1}, 2, ids, data));
    ASSERT_EQ(received_phases(to, 1).size(), 1u) << "block " << i << " not received";
    from.flush(Seconds(10));  // acknowledged by every matched reader
  }
}

constexpr int kMoreBlocks = 100;

// The heap in use after `send_more` less before it, in MB.
template <class SendMore>
double heap_growth_mb(SendMore send_more) {
  const std::size_t before = heap_in_use();
  send_more();
  return (static_cast<double>(heap_in_use()) - static_cast<double>(before)) / kMB;
}

TEST(DdsWriterHistory, AWriterWithVolatileReadersDropsItsAcknowledgedSamples) {
  static_assert(kDropAcknowledgedEvery < kVolatileWriterHistory);
  std::vector<std::unique_ptr<Session>> sessions;
  sessions.push_back(std::make_unique<CoordinatorSession>(options_for(true, 0)));
  sessions.push_back(std::make_unique<AgentSession>(options_for(false, 0)));
  sessions.push_back(std::make_unique<AgentSession>(options_for(false, 1)));
  AgentSession& a0 = static_cast<AgentSession&>(*sessions[1]);
  AgentSession& a1 = static_cast<AgentSession&>(*sessions[2]);
  ASSERT_NO_FATAL_FAILURE(pass_readiness_barriers(sessions, Seconds(30)));

  // Past the first drop: the payload pools of both ends hold what one cycle needs.
  ASSERT_NO_FATAL_FAILURE(send_one_at_a_time(a0, a1, 2 * kDropAcknowledgedEvery));
  // 100 more blocks: kept, they would be 100 x 128 KB = 12.5 MB more.
  const double grown_mb = heap_growth_mb([&] { send_one_at_a_time(a0, a1, kMoreBlocks); });
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_LT(grown_mb, 3.0) << "the writer kept its acknowledged samples";
}

// The same for an online mission's channels: agent 0 sends its blocks to agent 1, each received
// and acknowledged before the next. Each channel's own reader receives its writes too: both
// are emptied, so only the writers' histories could hold the blocks.
void send_one_at_a_time(OnlineChannel& from, OnlineChannel& to, int count) {
  std::vector<std::uint32_t> ids(kPoses);
  for (std::size_t i = 0; i < kPoses; ++i) ids[i] = static_cast<std::uint32_t>(i);
  const std::vector<double> data(4 * kPoses, 1.0);
  for (int i = 0; i < count; ++i) {
    from.send(pose_block_to({1}, 2, ids, data), 1);
    std::size_t got = 0;
    for (int wait = 0; wait < 100 && got == 0; ++wait) {
      to.wait(0.1);
      got = to.take_messages().size();
    }
    ASSERT_EQ(got, 1u) << "block " << i << " not received";
    from.flush(10.0);  // acknowledged by every matched reader
    from.take_messages();
  }
}

TEST(DdsWriterHistory, AnOnlineAgentsBlockWriterDropsItsAcknowledgedSamples) {
  const std::string run = "writer-history-online";
  OnlineChannel a0(kOnlineDomain, run, 0, kAgents);
  OnlineChannel a1(kOnlineDomain, run, 1, kAgents);
  // Both channels' writers and readers matched (each counts itself).
  for (int wait = 0; wait < 300; ++wait) {
    if (a0.matched_peers() >= 2 && a1.matched_peers() >= 2) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_GE(a0.matched_peers(), 2);
  ASSERT_GE(a1.matched_peers(), 2);

  ASSERT_NO_FATAL_FAILURE(send_one_at_a_time(a0, a1, 2 * kDropAcknowledgedEvery));
  // 100 more blocks: kept, they would be 100 x 128 KB = 12.5 MB more.
  const double grown_mb = heap_growth_mb([&] { send_one_at_a_time(a0, a1, kMoreBlocks); });
  ASSERT_FALSE(HasFatalFailure());
  EXPECT_LT(grown_mb, 3.0) << "the writer kept its acknowledged samples";
}

}  // namespace
