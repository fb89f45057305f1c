#include "runtime/team_memory.hpp"

#include <tessera/solvers/block_preconditioner.hpp>

namespace tessera::agent {

std::size_t team_factor_cap(std::uint32_t num_agents) {
  const std::size_t full = BlockPreconditioner::kDefaultMaxFactorEntries;
  if (num_agents <= kFullFactorAgents) return full;
  return full * kFullFactorAgents / num_agents;
}

}  // namespace tessera::agent
