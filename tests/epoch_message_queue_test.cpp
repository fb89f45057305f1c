// The online agent's queue of received protocol messages (runtime/epoch_message_queue.hpp):
// this epoch's messages for this agent are handled in arrival order, later epochs' wait for
// their solve, the rest goes, and once the solve is done the queue stays as it is.

#include "runtime/epoch_message_queue.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace tessera {
namespace {

struct Sample {
  std::uint32_t epoch = 0, sender = 0;
  bool broadcast = true;
  std::vector<std::uint32_t> recipients;
  int id = 0;  // stands for the message
};

Sample to(std::uint32_t epoch, std::uint32_t sender, std::vector<std::uint32_t> recipients,
          int id) {
  return {epoch, sender, recipients.empty(), std::move(recipients), id};
}

TEST(EpochMessageQueue, ThisEpochsMessagesForThisAgentAreHandledInOrderAndLaterOnesWait) {
  runtime::EpochMessageQueue<Sample> q;
  q.push(to(5, 1, {}, 1));      // broadcast by block 1: handled
  q.push(to(6, 1, {}, 2));      // the next epoch's: waits
  q.push(to(5, 0, {}, 3));      // this agent's own broadcast: goes
  q.push(to(5, 2, {1}, 4));     // for block 1 only: goes
  q.push(to(4, 1, {}, 5));      // a solve that ended: goes
  q.push(to(5, 2, {1, 0}, 6));  // for blocks 1 and 0: handled
  std::vector<int> handled;
  EXPECT_TRUE(q.take(
      5, 0, [&](const Sample& m) { handled.push_back(m.id); }, [] { return false; }));
  EXPECT_EQ(handled, (std::vector<int>{1, 6}));
  ASSERT_EQ(q.size(), 1u);
  handled.clear();
  EXPECT_FALSE(q.take(
      5, 0, [&](const Sample& m) { handled.push_back(m.id); }, [] { return false; }));
  EXPECT_TRUE(handled.empty());
  EXPECT_TRUE(q.take(
      6, 0, [&](const Sample& m) { handled.push_back(m.id); }, [] { return false; }));
  EXPECT_EQ(handled, (std::vector<int>{2}));
  EXPECT_EQ(q.size(), 0u);
}

TEST(EpochMessageQueue, OnceTheSolveIsDoneTheRestStaysQueuedAsItIs) {
  runtime::EpochMessageQueue<Sample> q;
  q.push(to(5, 1, {}, 1));
  q.push(to(5, 2, {}, 2));
  q.push(to(4, 1, {}, 3));  // old, but not looked at: stays
  std::vector<int> handled;
  EXPECT_TRUE(q.take(
      5, 0, [&](const Sample& m) { handled.push_back(m.id); }, [&] { return !handled.empty(); }));
  EXPECT_EQ(handled, (std::vector<int>{1}));
  EXPECT_EQ(q.size(), 2u);
  q.drop_before(5);  // a take-over abandons the epochs below 5
  EXPECT_EQ(q.size(), 1u);
  EXPECT_TRUE(q.take(
      5, 0, [&](const Sample& m) { handled.push_back(m.id); }, [] { return false; }));
  EXPECT_EQ(handled, (std::vector<int>{1, 2}));
}

}  // namespace
}  // namespace tessera
