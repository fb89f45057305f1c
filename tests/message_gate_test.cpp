// MessageGate (no DDS): one agent's incoming messages wait by (round, step) until the step it
// waits for has every sender's, and are then handed over in sender-id order. A step may be a
// whole 32-bit wire phase (the GNC agent keys its exchanges so), and a caller that forwards a
// whole stage to another protocol takes every stored message of a range of steps at once.

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <tessera/distributed/message_gate.hpp>
#include <tuple>
#include <vector>

namespace tessera {
namespace {

// A message that names itself: its round, phase and sender, and one value.
ProtocolMessage message(int sender, std::uint32_t round, std::uint32_t phase, double value = 0) {
  return make_reduction_message(sender, round, phase, {value});
}

std::tuple<std::uint32_t, std::uint32_t, std::uint32_t> id(const ProtocolMessage& m) {
  return {message_phase(m), message_round(m), message_sender(m)};
}

TEST(MessageGate, WaitsForEverySenderThenHandsTheStepOverInSenderOrder) {
  MessageGate gate;
  gate.expect(4, 2, {3, 1, 2});
  EXPECT_EQ(gate.senders(), (std::vector<int>{3, 1, 2}));
  EXPECT_TRUE(gate.add(2, 4, 2, message(2, 4, 2, 20.0)));
  EXPECT_TRUE(gate.add(1, 5, 2, message(1, 5, 2)));  // the next round's: waits
  EXPECT_TRUE(gate.add(3, 4, 2, message(3, 4, 2, 30.0)));
  EXPECT_FALSE(gate.add(3, 4, 2, message(3, 4, 2)));  // the same (round, step, sender) again
  EXPECT_EQ(gate.missing(), (std::vector<int>{1}));
  EXPECT_FALSE(gate.take_ready().has_value());
  EXPECT_TRUE(gate.add(1, 4, 2, message(1, 4, 2, 10.0)));
  const std::optional<MessageGate::Inbox> ready = gate.take_ready();
  ASSERT_TRUE(ready.has_value());
  std::vector<int> order;
  for (const auto& [sender, m] : *ready) order.push_back(sender);
  EXPECT_EQ(order, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(reduce_in_id_order(*ready, 1), (std::vector<double>{60.0}));
  EXPECT_FALSE(gate.take_ready().has_value());  // taken out of the gate
}

TEST(MessageGate, StepsBeyondSixteenBitsDoNotMeetAnotherRoundsStep) {
  // (round 1, step 1) and (round 0, step 65537) shared a key while steps had 16 bits.
  const std::uint32_t big = 65537;
  MessageGate gate;
  EXPECT_TRUE(gate.add(1, 1, 1, message(1, 1, 1)));
  EXPECT_TRUE(gate.add(1, 0, big, message(1, 0, big)));
  const std::uint32_t phase = 3000000u * 7 + 999005u;  // a GNC exchange's phase
  EXPECT_TRUE(gate.add(1, 0, phase, message(1, 0, phase)));
  gate.expect(0, big, {1});
  std::optional<MessageGate::Inbox> ready = gate.take_ready();
  ASSERT_TRUE(ready.has_value());
  EXPECT_EQ(id(ready->at(1)), std::make_tuple(big, 0u, 1u));
  gate.expect(0, phase, {1});
  ready = gate.take_ready();
  ASSERT_TRUE(ready.has_value());
  EXPECT_EQ(id(ready->at(1)), std::make_tuple(phase, 0u, 1u));
  gate.expect(1, 1, {1});
  EXPECT_TRUE(gate.take_ready().has_value());
}

TEST(MessageGate, TakeStepsHandsOverARangeOfStepsInStepRoundSenderOrderAndKeepsTheRest) {
  MessageGate gate;
  // Added out of order, as a transport may deliver them.
  gate.add(2, 1, 5, message(2, 1, 5));
  gate.add(0, 0, 7, message(0, 0, 7));
  gate.add(1, 1, 5, message(1, 1, 5));
  gate.add(1, 0, 5, message(1, 0, 5));
  gate.add(1, 0, 2, message(1, 0, 2));  // below the range
  gate.add(1, 0, 8, message(1, 0, 8));  // the range's end: not taken
  gate.add(3, 2, 3, message(3, 2, 3));
  const std::vector<ProtocolMessage> taken = gate.take_steps(3, 8);
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> ids;
  for (const auto& m : taken) ids.push_back(id(m));
  using T = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>;
  EXPECT_EQ(ids, (std::vector<T>{T{3, 2, 3}, T{5, 0, 1}, T{5, 1, 1}, T{5, 1, 2}, T{7, 0, 0}}));
  EXPECT_TRUE(gate.take_steps(3, 8).empty());  // removed from the gate
  gate.expect(0, 2, {1});
  EXPECT_TRUE(gate.take_ready().has_value());
  gate.expect(0, 8, {1});
  EXPECT_TRUE(gate.take_ready().has_value());
}

}  // namespace
}  // namespace tessera
