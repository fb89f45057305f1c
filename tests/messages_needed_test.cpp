// AgentProcess::messages_needed (no DDS): the DDS agent sleeps until that many protocol
// messages have arrived, so the count must be a lower bound -- handing an agent fewer messages
// than it said it needs never lets it move on (no output, not done) -- and it must not be a
// useless 1 everywhere: a status step of N agents waits for N - 1 statuses.

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <memory>
#include <optional>
#include <tessera/distributed/round_protocol.hpp>
#include <vector>

#include "random_graph.hpp"
#include "round_agents.hpp"

namespace tessera {
namespace {

// Four round protocols on an 80-pose random graph cut into contiguous blocks, started, and
// their queues: post() hands a step's output to every recipient but the sender, as a transport.
struct FourAgents {
  static constexpr int N = 4;
  PoseGraph g = graph();
  test::AgentsOfRun built{g, N, options()};
  std::vector<std::unique_ptr<RoundProtocol>>& agents = built.protocols;
  std::vector<std::deque<ProtocolMessage>> queue = std::vector<std::deque<ProtocolMessage>>(N);

  FourAgents(const FourAgents&) = delete;  // the agents hold references into it
  FourAgents& operator=(const FourAgents&) = delete;
  FourAgents() {
    for (int a = 0; a < N; ++a) post(a, agents[static_cast<std::size_t>(a)]->start());
  }

  static PoseGraph graph() {
    test::RandomGraphSpec spec;
    spec.d = 2;
    spec.poses = 80;
    spec.loop_closures = 40;
    spec.seed = 5;
    return test::random_pose_graph(spec);
  }
  static DistributedOptions options() {
    DistributedOptions opt;
    opt.max_rounds = 30;
    return opt;
  }

  void post(int from, const std::vector<OutgoingMessage>& out) {
    for (const auto& m : out)
      for (int a = 0; a < N; ++a) {
        if (a == from) continue;
        bool to_a = m.broadcast;
        for (auto r : m.recipients) to_a = to_a || static_cast<int>(r) == a;
        if (to_a) queue[static_cast<std::size_t>(a)].push_back(m.message);
      }
  }
};

TEST(MessagesNeeded, IsALowerBoundOnWhatEachStepWaitsFor) {
  FourAgents run;
  const int N = FourAgents::N;
  auto& agents = run.agents;
  auto& queue = run.queue;
  auto post = [&](int from, const std::vector<OutgoingMessage>& out) { run.post(from, out); };

  // Each agent in turn takes exactly messages_needed() messages when that many are queued
  // (as the DDS agent wakes then): the first needed - 1 of them must leave it where it was.
  std::size_t max_needed = 0, steps = 0;
  for (int sweep = 0; sweep < 100000; ++sweep) {
    bool all_done = true, moved = false;
    for (int a = 0; a < N; ++a) {
      RoundProtocol& p = *agents[static_cast<std::size_t>(a)];
      auto& q = queue[static_cast<std::size_t>(a)];
      if (p.done()) continue;
      all_done = false;
      const std::size_t needed = p.messages_needed();
      ASSERT_GE(needed, 1u) << "agent " << a << " runs but says it needs nothing";
      if (q.size() < needed) continue;
      max_needed = std::max(max_needed, needed);
      ++steps;
      for (std::size_t k = 0; k < needed; ++k) {
        const ProtocolMessage m = std::move(q.front());
        q.pop_front();
        const int round = p.rounds();
        const auto out = p.handle(m);
        if (k + 1 < needed) {
          ASSERT_TRUE(out.empty())
              << "agent " << a << " moved on after " << k + 1 << " of " << needed << " messages";
          ASSERT_FALSE(p.done());
          ASSERT_EQ(p.rounds(), round);
        }
        post(a, out);
      }
      moved = true;
    }
    if (all_done) break;
    ASSERT_TRUE(moved) << "no agent had the messages it said it needs: the count is too high";
  }
  for (int a = 0; a < N; ++a) {
    EXPECT_TRUE(agents[static_cast<std::size_t>(a)]->done());
    EXPECT_EQ(agents[static_cast<std::size_t>(a)]->messages_needed(), 0u);
    EXPECT_EQ(agents[static_cast<std::size_t>(a)]->rounds(), agents[0]->rounds());
  }
  EXPECT_GT(agents[0]->rounds(), 2);
  EXPECT_EQ(max_needed, static_cast<std::size_t>(N - 1));  // a status step: every other agent
  EXPECT_GT(steps, static_cast<std::size_t>(agents[0]->rounds()));
}

// AgentProcess::awaited names the messages the step lacks (the DDS agent sleeps until all of
// them are queued): handing the agent everything else queued never moves it on,
// the named ones do, with the last of them -- and the agents still run the same rounds.
TEST(MessagesNeeded, AwaitedNamesExactlyTheMessagesThatCompleteTheStep) {
  FourAgents run;
  const int N = FourAgents::N;
  auto& agents = run.agents;
  auto& queue = run.queue;
  auto post = [&](int from, const std::vector<OutgoingMessage>& out) { run.post(from, out); };

  std::size_t steps = 0, held_back = 0;
  for (int sweep = 0; sweep < 100000; ++sweep) {
    bool all_done = true, moved = false;
    for (int a = 0; a < N; ++a) {
      RoundProtocol& p = *agents[static_cast<std::size_t>(a)];
      auto& q = queue[static_cast<std::size_t>(a)];
      if (p.done()) {
        EXPECT_FALSE(p.awaited().has_value());
        continue;
      }
      all_done = false;
      const std::optional<AwaitedMessages> awaited = p.awaited();
      ASSERT_TRUE(awaited.has_value()) << "agent " << a << " runs but names nothing";
      ASSERT_EQ(awaited->senders.size(), p.messages_needed());
      if (!all_awaited_in(*awaited, q)) continue;  // the DDS agent sleeps on
      ++steps;
      // Everything else first (messages of later steps): none of it may move the step on.
      std::deque<ProtocolMessage> named;
      const int round = p.rounds();
      for (auto& m : q) {
        if (is_awaited(*awaited, m)) {
          named.push_back(std::move(m));
          continue;
        }
        ++held_back;
        const auto out = p.handle(m);
        ASSERT_TRUE(out.empty()) << "agent " << a << " moved on without an awaited message";
        ASSERT_EQ(p.rounds(), round);
      }
      q.clear();
      ASSERT_EQ(named.size(), awaited->senders.size());
      for (std::size_t k = 0; k < named.size(); ++k) {
        const auto out = p.handle(named[k]);
        if (k + 1 < named.size()) {
          ASSERT_TRUE(out.empty()) << "agent " << a << " moved on before its last awaited message";
        }
        post(a, out);
      }
      const std::optional<AwaitedMessages> next = p.awaited();
      ASSERT_TRUE(p.done() || next->round != awaited->round || next->phase != awaited->phase)
          << "agent " << a << " did not move on with every awaited message";
      moved = true;
    }
    if (all_done) break;
    ASSERT_TRUE(moved) << "no agent had every message it named";
  }
  for (int a = 0; a < N; ++a) {
    EXPECT_TRUE(agents[static_cast<std::size_t>(a)]->done());
    EXPECT_EQ(agents[static_cast<std::size_t>(a)]->rounds(), agents[0]->rounds());
  }
  EXPECT_GT(agents[0]->rounds(), 2);
  EXPECT_GT(steps, static_cast<std::size_t>(agents[0]->rounds()));
  EXPECT_GT(held_back, 0u);  // some agent did have later steps' messages queued
}

}  // namespace
}  // namespace tessera
