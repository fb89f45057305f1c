#pragma once
// One host's budget for the agents' exact block factors.
//
// Each agent keeps one exact factor for its block updates when CHOLMOD predicts at most a cap
// of entries: the tangent one, else its block's Q_BB one (also the certificate's), else it uses
// the block diagonal (solvers/block_preconditioner.hpp, solvers/tangent_preconditioner.hpp).
// The cap, 16 M entries (~190 MB with the factor's indices), bounds one agent; a team on one
// host holds one factor per agent: 64 agents of a 1M-pose 3D grid (15,625-pose blocks, Q_BB
// factors of ~160 MB under the cap, measured with the agents' memory lines) took the run from
// 6 GB in the initialisation to 16.6 GB in the block set-up, and the host's memory ran out. So
// above kFullFactorAgents agents the cap shrinks with the team: the factors of a whole team never
// exceed what kFullFactorAgents agents may hold (8 x 128 MB).

#include <cstddef>
#include <cstdint>

namespace tessera::agent {

/// Agents that each keep core's full cap.
constexpr std::uint32_t kFullFactorAgents = 8;

/// The factor cap of each agent of a team of `num_agents` (>= 1): core's default up to
/// kFullFactorAgents agents, then that default times kFullFactorAgents / num_agents.
std::size_t team_factor_cap(std::uint32_t num_agents);

}  // namespace tessera::agent
