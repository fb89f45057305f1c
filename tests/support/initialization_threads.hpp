#pragma once
// The agents' initialisation stage (runtime/initialization_stage.hpp) of a whole team in one
// process: each agent in its own thread over an in-memory channel (thread_exchange.hpp), for the
// tests that compare the stage's poses with core's initialisation bit for bit.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <utility>
#include <vector>

#include "runtime/early_chordal.hpp"
#include "runtime/initialization_stage.hpp"
#include "runtime/local_share.hpp"
#include "runtime/setup_turns.hpp"

namespace tessera::test {

/// Every measurement's endpoints in file order: the structure the coordinator sends.
std::vector<std::pair<std::uint32_t, std::uint32_t>> structure_of(const PoseGraph& g);

struct StageThreadsRun {
  std::vector<agent::RobotShare> shares;             ///< agent k's: robot_share(g, k, N)
  std::vector<agent::InitializationResult> results;  ///< agent k's
  std::size_t left_over = 0;  ///< messages no agent took (ThreadExchange::left_over)
  /// Every agent's poses, agent 0's first: the graph's poses in id order.
  std::vector<Pose> poses() const;
};

/// Runs run_initialization_stage(`method`) for agents 0..N-1 of `g`, each in its own thread,
/// with a 20 s timeout; agent 0 gets `early`, agent k the turns `turns_of(k)` (none when
/// empty). Expects every agent to finish without an exception.
StageThreadsRun run_initialization_threads(
    const PoseGraph& g, std::uint32_t N, const std::string& method,
    agent::EarlyChordal* early = nullptr,
    const std::function<agent::SetupTurnOptions(std::uint32_t)>& turns_of = nullptr);

/// Asserts that `a` and `b` are the same poses bit for bit, naming the first that differs.
void expect_identical(const std::vector<Pose>& a, const std::vector<Pose>& b);

}  // namespace tessera::test
