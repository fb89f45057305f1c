// The coordinator's decisions on lost agents (RejoinArbiter), without processes: which rollback
// round is chosen and when it gives up.

#include "runtime/rejoin_arbiter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <tessera/util/input_error.hpp>

namespace tessera::coordinator {
namespace {

using Kind = LossDecision::Kind;
const Clock::time_point t0 = Clock::now();
Clock::time_point at(double s) {
  return t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

TEST(RejoinArbiter, WaitsThenRollsBackToTheNewestCheckpointRoundEveryoneReached) {
  RejoinArbiter a(3, 10.0);
  for (std::uint32_t k = 0; k < 3; ++k) a.on_status(k, 7);
  a.on_status(0, 8);
  EXPECT_EQ(a.decide(at(0)).kind, Kind::kWait);
  a.on_lost(1, at(1));
  EXPECT_EQ(a.decide(at(5)).kind, Kind::kWait) << "inside the rejoin window";
  // Checkpoints at 6 and 8: agent 2 only reached 7, so 8 is not common; 6 is.
  a.on_rejoin({1, 8, 6, 42}, at(6));
  LossDecision d = a.decide(at(6));
  ASSERT_EQ(d.kind, Kind::kRollback);
  EXPECT_EQ(d.round, 6u);
  EXPECT_EQ(d.epoch, 1u);
  ASSERT_EQ(d.rejoined.size(), 1u);
  EXPECT_EQ(d.rejoined[0].nonce, 42u);
  EXPECT_FALSE(a.anyone_lost());
  EXPECT_EQ(a.decide(at(7)).kind, Kind::kWait);
  // A second loss: everyone reached 9 by now, the newest checkpoint wins; the epoch grows.
  for (std::uint32_t k = 0; k < 3; ++k) a.on_status(k, 9);
  a.on_rejoin({2, 9, 8, 7}, at(8));  // a rejoin before the loss was noticed counts as one
  d = a.decide(at(8));
  ASSERT_EQ(d.kind, Kind::kRollback);
  EXPECT_EQ(d.round, 9u);
  EXPECT_EQ(d.epoch, 2u);
}

TEST(RejoinArbiter, GivesUpWhenNobodyComesBackOrNoRoundIsCommon) {
  RejoinArbiter a(2, 3.0);
  a.on_status(0, 4);
  a.on_status(1, 4);
  a.on_lost(0, at(0));
  EXPECT_EQ(a.decide(at(2.9)).kind, Kind::kWait);
  const LossDecision d = a.decide(at(3.0));
  ASSERT_EQ(d.kind, Kind::kGiveUp);
  EXPECT_EQ(d.agent, 0u);
  EXPECT_NE(d.reason.find("did not rejoin within 3 s"), std::string::npos) << d.reason;

  RejoinArbiter b(2, 3.0);
  b.on_status(0, 2);
  b.on_status(1, 2);
  b.on_rejoin({1, 6, 5, 1}, at(0));  // agent 0 never reached 5
  const LossDecision e = b.decide(at(0));
  ASSERT_EQ(e.kind, Kind::kGiveUp);
  EXPECT_NE(e.reason.find("rounds reached: 0:2"), std::string::npos) << e.reason;

  RejoinArbiter off(2, 0.0);
  off.on_lost(1, at(0));
  EXPECT_EQ(off.decide(at(0)).kind, Kind::kGiveUp);
}

}  // namespace
}  // namespace tessera::coordinator
