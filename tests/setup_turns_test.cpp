// Turns of the distributed initialisation's local solves (core/runtime/setup_turns.hpp):
//  - the rule: agent a waits for agent a - K, so at most K agents solve at once, every agent
//    gets its turn, and the turns' count is the longest chain;
//  - the stage (in process, threads and an in-memory channel): the local solves finish in the
//    turns' order, and the poses are core's distributed initialisation bit for bit.

#include "runtime/setup_turns.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <mutex>
#include <random>
#include <string>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "initialization_threads.hpp"
#include "test_support.hpp"

namespace tessera::test {
namespace {

using agent::setup_turn;
using agent::SetupTurn;

TEST(SetupTurns, ZeroOrABoundAtLeastTheTeamMeansNobodyWaits) {
  for (std::uint32_t n : {1u, 5u, 64u})
    for (std::uint32_t k : {0u, n, n + 3}) {
      for (std::uint32_t a = 0; a < n; ++a) {
        const SetupTurn t = setup_turn(a, n, k);
        EXPECT_FALSE(t.waits_for.has_value()) << a << " of " << n << ", K " << k;
        EXPECT_FALSE(t.passes_to.has_value());
        EXPECT_EQ(t.position, 0u);
        EXPECT_EQ(t.chain_length, 1u);
      }
    }
}

TEST(SetupTurns, EachWaitIsForAnEarlierAgentThatPassesTheTurnToIt) {
  for (std::uint32_t n = 1; n <= 70; ++n)
    for (std::uint32_t k = 1; k <= n; ++k)
      for (std::uint32_t a = 0; a < n; ++a) {
        const SetupTurn t = setup_turn(a, n, k);
        if (t.waits_for) {
          ASSERT_LT(*t.waits_for, a);
          const SetupTurn before = setup_turn(*t.waits_for, n, k);
          ASSERT_TRUE(before.passes_to.has_value());
          ASSERT_EQ(*before.passes_to, a);
          ASSERT_EQ(t.position, before.position + 1);
        } else {
          ASSERT_EQ(t.position, 0u);
        }
        ASSERT_LT(t.position, t.chain_length);
      }
}

// Every agent's solve starts when the one it waits for has ended (random durations): never
// more than K at once, K at once at the start, and the last solve ends after chain_length turns
// of the longest duration at most.
TEST(SetupTurns, NeverMoreThanTheBoundSolveAtOnce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> duration(0.5, 3.0);
  for (std::uint32_t n : {1u, 2u, 7u, 25u, 64u, 65u})
    for (std::uint32_t k : {1u, 2u, 3u, 8u, 16u}) {
      std::vector<double> start(n), end(n);
      for (std::uint32_t a = 0; a < n; ++a) {  // waits_for < a: already placed
        const SetupTurn t = setup_turn(a, n, k);
        start[a] = t.waits_for ? end[*t.waits_for] : 0.0;
        end[a] = start[a] + duration(rng);
      }
      std::size_t most = 0;
      for (std::uint32_t a = 0; a < n; ++a) {
        // Solves running just after a's start (intervals [start, end)).
        std::size_t running = 0;
        for (std::uint32_t b = 0; b < n; ++b)
          if (start[b] <= start[a] && start[a] < end[b]) ++running;
        most = std::max(most, running);
      }
      EXPECT_EQ(most, std::min<std::size_t>(k, n)) << n << " agents, K " << k;
      const double last = *std::max_element(end.begin(), end.end());
      EXPECT_LE(last, 3.0 * setup_turn(0, n, k).chain_length) << n << " agents, K " << k;
      EXPECT_EQ(setup_turn(0, n, k).chain_length, (n + std::min(k, n) - 1) / std::min(k, n));
    }
}

TEST(SetupTurns, ABoundOutOfRangeIsRefusedByName) {
  agent::SetupTurnOptions o;
  o.max_at_once = agent::SetupTurnOptions::kMaxSetupAtOnce + 1;
  EXPECT_TRUE(test::validation_names(o, "max_at_once"));
  o.max_at_once = 0;
  EXPECT_NO_THROW(o.validate());
  EXPECT_THROW(setup_turn(5, 5, 2), std::invalid_argument);
}

// Runs the distributed initialisation of `g` over `n` agents in threads with turns of
// `max_at_once`; returns the poses in global order and the order the local solves ended in.
std::vector<Pose> run_with_turns(const PoseGraph& g, std::uint32_t n, std::uint32_t max_at_once,
                                 std::vector<std::uint32_t>* solve_order, std::size_t* leftover) {
  std::mutex mu;
  const StageThreadsRun run =
      run_initialization_threads(g, n, "distributed", nullptr, [&](std::uint32_t k) {
        agent::SetupTurnOptions turns;
        turns.max_at_once = max_at_once;
        turns.after_local_solve = [&, k] {
          std::lock_guard<std::mutex> lock(mu);
          solve_order->push_back(k);
        };
        return turns;
      });
  *leftover = run.left_over;
  return run.poses();
}

TEST(InitializationTurns, LocalSolvesEndInTurnOrderAndThePosesAreCores) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 300;
  o.num_robots = 6;
  o.seed = 3;
  const PoseGraph g = generate_pose_graph(o).graph;
  const std::vector<Pose> reference = initial_poses(g, DistributedInit::kDistributed, 6);
  for (std::uint32_t k : {0u, 1u, 2u, 4u}) {
    std::vector<std::uint32_t> order;
    std::size_t leftover = 1;
    expect_identical(run_with_turns(g, 6, k, &order, &leftover), reference);
    EXPECT_EQ(leftover, 0u) << "K " << k << ": every turn message is consumed in the stage";
    ASSERT_EQ(order.size(), 6u) << "K " << k;
    // Agent a's solve ends after agent a - K's (K = 1: strictly one after the other).
    std::vector<std::size_t> at(6);
    for (std::size_t i = 0; i < order.size(); ++i) at[order[i]] = i;
    for (std::uint32_t a = 0; a < 6; ++a) {
      const SetupTurn t = setup_turn(a, 6, k);
      if (t.waits_for) {
        EXPECT_LT(at[*t.waits_for], at[a]) << "K " << k << ", agent " << a;
      }
    }
    if (k == 1) {
      EXPECT_EQ(order, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
    }
  }
}

}  // namespace
}  // namespace tessera::test
