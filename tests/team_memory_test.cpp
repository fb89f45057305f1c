// One host's budget for the agents' exact block factors (core/runtime/team_memory.hpp).

#include "runtime/team_memory.hpp"

#include <gtest/gtest.h>

#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/solvers/block_preconditioner.hpp>

#include "runtime/round_loop.hpp"

namespace tessera::test {
namespace {

constexpr std::size_t kFull = BlockPreconditioner::kDefaultMaxFactorEntries;

TEST(TeamMemory, SmallTeamsKeepCoresCapLargeOnesShareItsBudget) {
  for (std::uint32_t n = 1; n <= agent::kFullFactorAgents; ++n)
    EXPECT_EQ(agent::team_factor_cap(n), kFull) << n << " agents";
  for (std::uint32_t n : {9u, 25u, 64u, 1000u}) {
    const std::size_t cap = agent::team_factor_cap(n);
    EXPECT_LT(cap, kFull) << n << " agents";
    EXPECT_GT(cap, 0u) << n << " agents: 0 would mean no cap at all";
    EXPECT_LE(cap * n, kFull * agent::kFullFactorAgents) << n << " agents";
  }
  EXPECT_EQ(agent::team_factor_cap(64), kFull / 8);
}

TEST(TeamMemory, TheCapReachesTheBlockUpdatesOnlyWhenSet) {
  agent::RunOptions o;
  EXPECT_EQ(agent::distributed_options_of(o).block_update.max_factor_entries, kFull);
  o.max_factor_entries = agent::team_factor_cap(64);
  EXPECT_EQ(agent::distributed_options_of(o).block_update.max_factor_entries, kFull / 8);
}

}  // namespace
}  // namespace tessera::test
