// Round-protocol steps on the listener thread that receives their message (docs/dds-runtime.md,
// "Session 12"): the router's consumer never makes a listener thread wait (a busy consumer runs
// once more instead), its writes never wait for acknowledgements (a full writer history sends
// them to a backlog the application thread writes), and DdsProtocolChannel::drive() brings
// every outcome (done, an exception of the step, a stop, the timeout) back to the waiting
// thread. Sessions of this process on DDS domain 8.

#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "agent/dds_channel.hpp"
#include "transport/epoch_routing.hpp"
#include "transport/session.hpp"

namespace {

using namespace tessera;
using namespace tessera::transport;
using std::chrono::seconds;

constexpr int kDomain = 8;  // this test's own domain (tests use 50-55, 100-232)

OutgoingMessage block(std::uint32_t sender, std::uint32_t round, std::uint32_t to) {
  PoseBlockMessage b;
  b.round = round;
  b.sender = sender;
  b.phase = 2;
  b.rank = 2;
  b.dim = 1;
  b.pose_ids = {3};
  b.data = {1.0, 2.0, 3.0, 4.0};
  return OutgoingMessage{b, false, {to}};
}

std::uint32_t round_of(const ProtocolMessage& m) {
  return std::visit([](const auto& x) { return x.round; }, m);
}

TEST(ListenerSteps, ABusyConsumerRunsAgainInsteadOfMakingAnotherThreadWait) {
  Mailroom room;
  Inbox<ProtocolMessage> inbox(room);
  EpochRouter router(room, inbox, 0);
  std::promise<void> entered, release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> calls{0};
  router.set_consumer([&] {
    if (++calls == 1) {
      entered.set_value();
      released.wait();
    }
  });
  std::thread first([&] { router.hand_over(); });
  entered.get_future().wait();
  // Another thread hands over while the first is inside the consumer: it returns at once.
  auto second = std::async(std::launch::async, [&] { router.hand_over(); });
  ASSERT_EQ(second.wait_for(seconds(30)), std::future_status::ready);
  EXPECT_EQ(calls.load(), 1);
  release.set_value();
  first.join();
  EXPECT_EQ(calls.load(), 2);  // the first thread ran it again for the second's message
  // While a consumer is set, a delivered message wakes no waiter (it is the consumer's).
  router.deliver(0, 1, true, {}, ProtocolMessage(PoseBlockMessage{}));
  EXPECT_EQ(room.wait_for([&] { return !inbox.queued_locked().empty(); }, Seconds(0)),
            WaitStatus::kReady);
  router.set_consumer(nullptr);
  router.hand_over();
  EXPECT_EQ(calls.load(), 2);
}

SessionOptions options_for(bool coordinator, std::uint32_t agent, const std::string& run) {
  SessionOptions o;
  o.run_id = run;
  o.domain = kDomain;
  o.coordinator = coordinator;
  o.agent_id = agent;
  o.num_agents = 2;
  o.lease_s = 3.0;           // no false peer loss on a loaded machine
  o.write_timeout_s = 60.0;  // a write that waited would stall the test for a minute
  return o;
}

// A coordinator and two agents past the readiness barrier.
std::vector<std::unique_ptr<Session>> ready_sessions(const std::string& run) {
  // As between processes: without this Fast DDS would run the reader's listener inside the
  // writer's write() (intra-process delivery), on the writing thread.
  eprosima::fastrtps::LibrarySettingsAttributes library;
  library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(library);
  std::vector<std::unique_ptr<Session>> sessions;
  sessions.push_back(std::make_unique<Session>(options_for(true, 0, run)));
  for (std::uint32_t k = 0; k < 2; ++k)
    sessions.push_back(std::make_unique<Session>(options_for(false, k, run)));
  std::vector<std::future<WaitStatus>> barriers;
  for (auto& s : sessions)
    barriers.push_back(std::async(std::launch::async, [&s] {
      std::string missing;
      return s->ready_barrier(Seconds(30), &missing);
    }));
  for (auto& b : barriers) EXPECT_EQ(b.get(), WaitStatus::kReady);
  return sessions;
}

TEST(ListenerSteps, WritesOfTheConsumerNeverWaitForAcknowledgements) {
  auto sessions = ready_sessions("listener-steps-backlog");
  Session& a0 = *sessions[1];
  Session& a1 = *sessions[2];
  // Agent 1's consumer holds its listener thread on the first message: that thread neither
  // reads nor acknowledges agent 0's samples any more, so agent 0's writer history fills.
  std::promise<void> stuck, release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<bool> holding{false};
  std::vector<std::uint32_t> rounds;  // touched by the consumer only, read after clearing it
  std::atomic<std::size_t> received{0};
  a1.set_protocol_consumer([&] {
    if (!holding.exchange(true)) {
      stuck.set_value();
      released.wait();
    }
    for (const auto& m : a1.protocol().take_all()) rounds.push_back(round_of(m));
    received = rounds.size();
  });
  a0.send(block(0, 0, 1));
  ASSERT_EQ(stuck.get_future().wait_for(seconds(30)), std::future_status::ready);
  // Agent 0 writes far more than its history holds from its consumer: nothing waits.
  constexpr std::uint32_t kWrites = 1000;
  a0.set_protocol_consumer([&] {
    for (std::uint32_t r = 1; r <= kWrites; ++r) a0.send(block(0, r, 1));
  });
  auto writing = std::async(std::launch::async, [&] { a0.consume_protocol(); });
  ASSERT_EQ(writing.wait_for(seconds(30)), std::future_status::ready)
      << "a write inside the consumer waited for acknowledgements";
  writing.get();
  a0.set_protocol_consumer(nullptr);
  EXPECT_TRUE(a0.writes_backlogged());
  // A waiting write wakes the mailroom's waiters (the application thread flushes).
  EXPECT_EQ(a0.mailroom().wait_for([&] { return a0.writes_backlogged(); }, Seconds(0)),
            WaitStatus::kReady);
  release.set_value();
  a0.flush_writes();  // waits for acknowledgements, as any other write
  EXPECT_FALSE(a0.writes_backlogged());
  a0.flush(Seconds(30));
  const auto until = std::chrono::steady_clock::now() + seconds(30);
  while (std::chrono::steady_clock::now() < until) {
    a1.consume_protocol();
    if (received.load() == kWrites + 1) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  a1.set_protocol_consumer(nullptr);
  ASSERT_EQ(rounds.size(), kWrites + 1);
  for (std::uint32_t r = 0; r <= kWrites; ++r) ASSERT_EQ(rounds[r], r) << "out of order";
}

TEST(ListenerSteps, DriveBringsEveryOutcomeBackToTheWaitingThread) {
  auto sessions = ready_sessions("listener-steps-drive");
  Session& a0 = *sessions[1];
  Session& a1 = *sessions[2];
  agent::DdsProtocolChannel channel(a1);
  using Drive = agent::ProtocolChannel::Drive;

  // Done: the step that returns true ends the wait; it ran on a listener thread.
  std::vector<std::uint32_t> rounds;
  std::thread::id step_thread;
  std::thread sender([&] {  // once drive() waits
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    a0.send(block(0, 1, 1));
    a0.send(block(0, 2, 1));
  });
  EXPECT_EQ(channel.drive(
                [&](ProtocolMessage&& m) {
                  rounds.push_back(round_of(m));
                  step_thread = std::this_thread::get_id();
                  return rounds.size() == 2;
                },
                30.0),
            Drive::kDone);
  sender.join();
  EXPECT_EQ(rounds, (std::vector<std::uint32_t>{1, 2}));
  EXPECT_NE(step_thread, std::this_thread::get_id());

  // An exception of the step is thrown on the waiting thread.
  a0.send(block(0, 3, 1));
  try {
    channel.drive([](ProtocolMessage&&) -> bool { throw std::runtime_error("bad block"); }, 30.0);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "bad block");
  }

  // Nothing arrives: the timeout.
  EXPECT_EQ(channel.drive([](ProtocolMessage&&) { return false; }, 0.5), Drive::kTimeout);

  // A stop ends the wait with RunStopped naming it.
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    a1.mailroom().request_stop(3, "stopped by the test");
  });
  EXPECT_THROW(
      {
        try {
          channel.drive([](ProtocolMessage&&) { return false; }, 30.0);
        } catch (const agent::RunStopped& e) {
          EXPECT_EQ(std::string(e.what()), "stopped by the test");
          throw;
        }
      },
      agent::RunStopped);
  stopper.join();
}

}  // namespace
