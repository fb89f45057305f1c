// Who takes part in each epoch of an online run over DDS (runtime/online_membership.hpp):
// agent 0 starts alone, the lead admits at the next epoch every agent heard from, an agent
// lost before its admission is not admitted, and a take-over moves the run to a fresh epoch
// whose members are the survivors.

#include "runtime/online_membership.hpp"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <vector>

namespace tessera {
namespace {

using Agents = std::vector<std::uint32_t>;

TEST(OnlineMembership, AgentZeroStartsAloneAsTheLead) {
  const runtime::OnlineMembership m(3);
  EXPECT_EQ(m.members(0), (std::set<std::uint32_t>{0}));
  EXPECT_EQ(m.lead_of(0), 0u);
  EXPECT_TRUE(m.absorbs(0, 0));
  EXPECT_FALSE(m.absorbs(1, 0));
  EXPECT_FALSE(m.joiner_waiting(0));
}

TEST(OnlineMembership, TheLeadAdmitsEveryAgentHeardFromAtTheNextEpoch) {
  runtime::OnlineMembership m(3);
  m.heard_from(2);
  m.heard_from(7);  // no robot of the run: never admitted
  EXPECT_TRUE(m.joiner_waiting(0));
  const Agents next = m.next_members(0, {});
  EXPECT_EQ(next, (Agents{0, 2}));
  m.admit(0, next);
  EXPECT_TRUE(m.is_member(2, 1));
  EXPECT_TRUE(m.absorbs(2, 1));
  EXPECT_FALSE(m.absorbs(1, 1));  // robot 1's data waits for its agent
  EXPECT_FALSE(m.joiner_waiting(1));
}

TEST(OnlineMembership, AnAgentLostBeforeItsAdmissionIsNotAdmitted) {
  runtime::OnlineMembership m(3);
  m.heard_from(1);
  m.heard_from(2);
  m.admit(0, {0, 1});
  // At epoch 1, agent 2 (heard from, not a member) and member 1 are both reported lost: only
  // the non-member is left out; a lost member is the take-over's business.
  EXPECT_EQ(m.next_members(1, {1, 2}), (Agents{0, 1}));
}

TEST(OnlineMembership, ATakeOverGoesOnWithTheSurvivorsAtAFreshEpoch) {
  runtime::OnlineMembership m(3);
  for (std::uint32_t a : {1u, 2u}) m.heard_from(a);
  m.admit(0, {0, 1, 2});
  m.admit(1, {0, 1, 2});
  m.taken_over({0}, {1, 2}, 5);
  EXPECT_EQ(m.members(5), (std::set<std::uint32_t>{1, 2}));
  EXPECT_EQ(m.lead_of(5), 1u);  // the lowest survivor leads
  EXPECT_TRUE(m.abandoned(4));
  EXPECT_FALSE(m.abandoned(5));
  EXPECT_THROW(static_cast<void>(m.members(1)), std::out_of_range);
  // The lost agent's robot is absorbed by its block's adopter; its agent is never heard from
  // (or admitted) again.
  EXPECT_TRUE(m.lost(0));
  EXPECT_TRUE(m.absorbs(0, 5));
  m.heard_from(0);
  EXPECT_FALSE(m.joiner_waiting(5));
  EXPECT_EQ(m.next_members(5, {}), (Agents{1, 2}));
}

TEST(OnlineMembership, WhatEntersIsWhatEveryMemberHoldsOfTheRobotsAbsorbedAtTheEpoch) {
  runtime::OnlineMembership m(4);
  m.admit(0, {0, 1, 2});
  m.taken_over({2}, {0, 1}, 3);
  // Epoch 3: members 0 and 1; robot 2's data goes to its block's adopter, robot 3's waits
  // for its agent.
  const Watermarks a{{0, 5}, {1, 4}, {2, 7}, {3, 2}};
  const Watermarks b{{0, 3}, {1, 6}, {2, 9}, {3, 2}};
  EXPECT_EQ(m.entering({a, b}, 3), (Watermarks{{0, 3}, {1, 4}, {2, 7}, {3, 0}}));
}

}  // namespace
}  // namespace tessera
