#pragma once
// Steps 1-6 of a fresh (not restarted) agent, in order: read this robot's share, announce
// its structure (endpoints only), receive and check the coordinator's assignment, wait
// until every process is ready, compute the initial poses, and hand measurements and poses
// to the agents that own them. Each step is its own file; this one sequences them.

#include <cstdint>

#include "agent/agent_options.hpp"
#include "runtime/agent_log.hpp"
#include "runtime/round_loop.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// What the rounds start from, and how the coordinator handles lost agents in this run.
struct RunSetup {
  AgentLocalData local;
  bool rejoin_enabled = false;       ///< The coordinator waits for lost agents to rejoin.
  std::uint32_t replicas = 0;        ///< Replicas of this agent's block (0: no re-partition).
  std::uint32_t replica_every = 10;  ///< Rounds between lifted-pose replicas, >= 1.
  bool status_relay = false;         ///< Round statuses through agent 0 (coordinator's choice).
};

/// Runs steps 1-6 (and writes --dump-local). Throws InputError on bad input files,
/// RunFailure on a stop, a timeout or an assignment that does not fit this agent.
RunSetup set_up_fresh_run(transport::AgentSession& session, const AgentOptions& options,
                          const AgentLog& log);

}  // namespace tessera::agent
