// The rounding's waits (agent::Mailbox::gather), without processes: each wait asks the channel
// to sleep until as many messages as the step still lacks have come, instead of waking for
// every message (docs/dds-runtime.md, "Round waits"), and never for more than that.

#include <gtest/gtest.h>

#include <deque>
#include <vector>

#include "runtime/distributed_rounding.hpp"
#include "runtime/round_mailbox.hpp"

namespace tessera::agent {
namespace {

// Hands out queued messages in order and records what each wait asked for.
class RecordingChannel : public ProtocolChannel {
 public:
  std::deque<ProtocolMessage> queued;
  std::vector<std::size_t> wake_after;

  void send(const OutgoingMessage&) override {}
  std::optional<ProtocolMessage> receive(double timeout_s) override {
    return receive_after(timeout_s, 1);
  }
  std::optional<ProtocolMessage> receive_after(double, std::size_t n) override {
    wake_after.push_back(n);
    if (queued.empty()) return std::nullopt;
    ProtocolMessage m = queued.front();
    queued.pop_front();
    return m;
  }
};

RoundStatusMessage status(std::uint32_t sender, std::uint32_t phase, std::uint32_t round) {
  RoundStatusMessage m;
  m.sender = sender;
  m.phase = phase;
  m.round = round;
  return m;
}

TEST(RoundingWakeups, EachWaitAsksForWhatTheStepStillLacks) {
  RecordingChannel ch;
  Mailbox mail(ch, 1.0, 0);
  ch.queued = {status(2, kCurvature, 0), status(1, kResidual, 0),  // the next step's, early
               status(1, kCurvature, 0), status(4, kCurvature, 0), status(3, kCurvature, 0)};
  const auto got = mail.gather(kCurvature, 0, {1, 2, 3, 4});
  EXPECT_EQ(got.size(), 4u);
  // 4 missing; 3 after agent 2's; still 3 after the early one; then 2, 1.
  EXPECT_EQ(ch.wake_after, (std::vector<std::size_t>{4, 3, 3, 2, 1}));
  EXPECT_TRUE(ch.queued.empty());

  // The next step already has agent 1's status: the first wait asks for the other three.
  ch.wake_after.clear();
  ch.queued = {status(3, kResidual, 0), status(2, kResidual, 0), status(4, kResidual, 0)};
  EXPECT_EQ(mail.gather(kResidual, 0, {1, 2, 3, 4}).size(), 4u);
  EXPECT_EQ(ch.wake_after, (std::vector<std::size_t>{3, 2, 1}));
}

TEST(RoundingWakeups, AMissingSenderStillEndsInAClearError) {
  RecordingChannel ch;
  Mailbox mail(ch, 1.0, 0);
  ch.queued = {status(1, kCost, 0)};
  try {
    mail.gather(kCost, 0, {1, 2});
    FAIL() << "gather returned without agent 2's status";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("waiting for agent(s) 2"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ch.wake_after, (std::vector<std::size_t>{2, 1}));
}

}  // namespace
}  // namespace tessera::agent
