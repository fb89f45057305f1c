// Where a distributed GNC agent's incoming messages go (robust/gnc_mailbox.hpp, no DDS): the
// running solve's at once; an exchange's once every sender's is in, in agent-id order; a faster
// agent's messages of later steps wait for them; messages of a step left behind are dropped.

#include "robust/gnc_mailbox.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <utility>
#include <vector>

namespace tessera {
namespace {

ProtocolMessage block(int sender, std::uint32_t round, std::uint32_t phase,
                      BlockKind kind = BlockKind::kY) {
  PoseBlockMessage m = make_reduction_message(sender, round, phase, {1.0});
  m.kind = kind;
  return m;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> sender_phase(
    const std::vector<ProtocolMessage>& ms) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
  for (const auto& m : ms) out.emplace_back(message_sender(m), message_phase(m));
  return out;
}

TEST(GncMailbox, AnExchangeIsReadInAgentIdOrderOnceEverySendersMessageIsIn) {
  GncMailbox mail(1);
  const std::uint32_t votes = gnc_phase(2, GncExchange::kVotes);
  mail.begin_exchange(votes, {0, 2, 3});
  EXPECT_FALSE(mail.add(block(3, 0, votes)));
  EXPECT_FALSE(mail.add(block(0, 0, votes)));
  EXPECT_FALSE(mail.take_exchange().has_value());
  EXPECT_EQ(mail.awaited().senders, (std::vector<std::uint32_t>{2}));
  EXPECT_EQ(mail.awaited().phase, votes);
  EXPECT_EQ(mail.messages_needed(), 1u);
  EXPECT_FALSE(mail.add(block(2, 0, votes)));
  const std::optional<std::vector<ProtocolMessage>> ready = mail.take_exchange();
  ASSERT_TRUE(ready.has_value());
  using P = std::pair<std::uint32_t, std::uint32_t>;
  EXPECT_EQ(sender_phase(*ready), (std::vector<P>{P{0, votes}, P{2, votes}, P{3, votes}}));
  EXPECT_FALSE(mail.take_exchange().has_value());  // read once
}

// RobustOptions::weights_ride_trial_sums: the trial's weights are read as the step's weight
// exchange after the solve. Agent 0, done with it first, may end GNC early and send the kept
// set's fresh start in the same step: that message waits for this agent, it is not dropped as
// one of a step left behind.
TEST(GncMailbox, TheKeptStartAfterTheTrialsWeightsWaitsForThisAgent) {
  GncMailbox mail(1);
  const std::uint32_t weights = gnc_phase(4, GncExchange::kTrialWeights);
  const std::uint32_t kept = gnc_phase(4, GncExchange::kKeptStart);
  const std::uint32_t rejected = gnc_phase(4, GncExchange::kRejected);
  EXPECT_LT(weights, rejected);
  mail.begin_exchange(weights, {0, 2});
  EXPECT_FALSE(mail.add(block(0, 0, weights)));
  EXPECT_FALSE(mail.add(block(0, 0, kept)));  // agent 0 is a step ahead
  EXPECT_FALSE(mail.take_exchange().has_value());
  EXPECT_FALSE(mail.add(block(2, 0, weights)));
  ASSERT_TRUE(mail.take_exchange().has_value());
  mail.begin_exchange(kept, {0});
  const std::optional<std::vector<ProtocolMessage>> ready = mail.take_exchange();
  ASSERT_TRUE(ready.has_value());  // it was kept
  EXPECT_EQ(message_phase(ready->front()), kept);
}

// RobustOptions::pass_poses_ride_trial_sums: an inlier pass's trial poses carry their trial's
// number in the wire's round; the pass's pose exchange takes the one trial it names, and a
// runtime waiting by (round, phase) is told that round.
TEST(GncMailbox, APassesPoseExchangeTakesTheTrialItNames) {
  GncMailbox mail(1);
  const std::uint32_t trials = gnc_phase(6, GncExchange::kPassTrialPoses);
  EXPECT_LT(trials, gnc_phase(6, GncExchange::kReadmitted));
  EXPECT_FALSE(mail.add(block(0, 1, trials)));  // trial 1 and 2 from agent 0, before the exchange
  EXPECT_FALSE(mail.add(block(0, 2, trials)));
  mail.discard(trials, 1);
  mail.begin_trial_exchange(trials, 2, {0, 2});
  EXPECT_FALSE(mail.take_exchange().has_value());
  EXPECT_EQ(mail.awaited().round, 2u);
  EXPECT_EQ(mail.awaited().senders, (std::vector<std::uint32_t>{2}));
  EXPECT_FALSE(mail.add(block(2, 2, trials)));
  const std::optional<std::vector<ProtocolMessage>> ready = mail.take_exchange();
  ASSERT_TRUE(ready.has_value());
  ASSERT_EQ(ready->size(), 2u);
  EXPECT_EQ(message_round(ready->front()), 2u);
  EXPECT_EQ(message_round(ready->back()), 2u);
}

TEST(GncMailbox, AFasterAgentsLaterStepsWaitAndAStepLeftBehindIsDropped) {
  GncMailbox mail(0);
  const std::uint32_t poses = gnc_phase(1, GncExchange::kPoses);
  mail.begin_exchange(poses, {1});
  // Agent 1 is ahead: step 2's solve (two rounds of it) and step 2's votes.
  const std::uint32_t solve2 = 2 * kGncStepStride + 3;
  const std::uint32_t votes2 = gnc_phase(2, GncExchange::kVotes);
  EXPECT_FALSE(mail.add(block(1, 1, solve2)));
  EXPECT_FALSE(mail.add(block(1, 0, solve2)));
  EXPECT_FALSE(mail.add(block(1, 0, votes2)));
  EXPECT_FALSE(mail.take_exchange().has_value());  // none of them is this exchange's
  EXPECT_FALSE(mail.add(block(1, 0, poses)));
  ASSERT_TRUE(mail.take_exchange().has_value());

  // Step 2's solve: what came early, by round; a straggler of step 1's solve is dropped.
  const std::vector<ProtocolMessage> early = mail.begin_solve(2);
  ASSERT_EQ(early.size(), 2u);
  EXPECT_EQ(message_round(early[0]), 0u);
  EXPECT_EQ(message_round(early[1]), 1u);
  EXPECT_TRUE(mail.add(block(1, 2, solve2)));  // the running solve's: handed over at once
  const std::uint32_t solve1 = 1 * kGncStepStride + 3;
  EXPECT_FALSE(mail.add(block(1, 5, solve1)));

  mail.begin_exchange(votes2, {1});
  const std::optional<std::vector<ProtocolMessage>> ready = mail.take_exchange();
  ASSERT_TRUE(ready.has_value());  // it was already in
  EXPECT_EQ(message_phase(ready->front()), votes2);
  EXPECT_TRUE(mail.begin_solve(1).empty());  // the straggler was not kept
}

TEST(GncMailbox, BothStartsPosesWaitForTheKindYAndTheKindPBlockOfEveryNeighbour) {
  GncMailbox mail(1);
  const std::uint32_t starts = gnc_phase(0, GncExchange::kStartPoses);
  mail.begin_exchange(starts, {0, 2});
  EXPECT_FALSE(mail.add(block(0, 0, starts, BlockKind::kP)));
  EXPECT_FALSE(mail.add(block(2, 0, starts, BlockKind::kP)));
  EXPECT_FALSE(mail.add(block(0, 0, starts, BlockKind::kY)));
  EXPECT_FALSE(mail.take_exchange().has_value());
  EXPECT_FALSE(mail.add(block(2, 0, starts, BlockKind::kY)));
  const std::optional<std::vector<ProtocolMessage>> ready = mail.take_exchange();
  ASSERT_TRUE(ready.has_value());
  ASSERT_EQ(ready->size(), 4u);
  std::vector<std::pair<std::uint32_t, BlockKind>> got;
  for (const auto& m : *ready)
    got.emplace_back(message_sender(m), std::get<PoseBlockMessage>(m).kind);
  using K = std::pair<std::uint32_t, BlockKind>;
  EXPECT_EQ(got, (std::vector<K>{K{0, BlockKind::kY}, K{2, BlockKind::kY}, K{0, BlockKind::kP},
                                 K{2, BlockKind::kP}}));
}

TEST(GncMailbox, AMessageTheExchangeDoesNotExpectOrASecondCopyIsAnError) {
  GncMailbox mail(1);
  const std::uint32_t rejected = gnc_phase(4, GncExchange::kRejected);
  mail.begin_exchange(rejected, {0});
  EXPECT_THROW(mail.add(block(2, 0, rejected)), std::runtime_error);
  const std::uint32_t later = gnc_phase(5, GncExchange::kVotes);
  EXPECT_FALSE(mail.add(block(0, 0, later)));
  EXPECT_THROW(mail.add(block(0, 0, later)), std::runtime_error);
}

}  // namespace
}  // namespace tessera
