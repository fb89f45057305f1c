#pragma once
// One host's budget for the agents' exact block factors.
//
// Each agent keeps the Cholesky factor of its block's Q_BB (the block updates' preconditioner,
// also the certificate's) when CHOLMOD predicts at most a cap of entries, else it uses the
// block diagonal (solvers/block_preconditioner.hpp). The cap, 16 M entries (128 MB), bounds one
// agent; a team on one host holds one factor per agent: 64 agents of a 1M-pose 3D grid
// (15,625-pose blocks, under the cap) took the run from 6 GB in the initialisation to 16.6 GB
// in the block set-up, and the host's memory ran out. So above kFullFactorAgents agents the
// cap shrinks with the team: the factors of a whole team never exceed what kFullFactorAgents
// agents may hold (8 x 128 MB).

#include <cstddef>
#include <cstdint>

namespace tessera::agent {

/// Agents that each keep core's full cap.
constexpr std::uint32_t kFullFactorAgents = 8;

/// The factor cap of each agent of a team of `num_agents` (>= 1): core's default up to
/// kFullFactorAgents agents, then that default times kFullFactorAgents / num_agents.
std::size_t team_factor_cap(std::uint32_t num_agents);

}  // namespace tessera::agent
