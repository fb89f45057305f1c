#pragma once
// The whole run on the agent's side: a fresh start (steps 1-6, run_setup.hpp) or, for a
// process restarted after a crash, its checkpoint; then the rounds, resumed from a snapshot
// on every coordinated rollback and moved to a new block on a re-partition for the
// survivors, until the coordinator confirms the merged result (final_report.hpp).

#include <optional>
#include <string>

#include "agent/agent_options.hpp"
#include "runtime/agent_checkpoint.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// This agent's checkpoint when --checkpoint-dir holds one (this process is a restart),
/// nullopt otherwise. A restart prints that it rejoins and waits 1.5 leases before the
/// session may open: the others drop the previous incarnation after one lease, and joining
/// earlier would look like two processes claiming this id. Throws CheckpointError naming the
/// file when it is damaged or belongs to another run or agent.
std::optional<AgentCheckpoint> find_restart_checkpoint(const AgentOptions& options);

/// Runs the agent on an open session (from `restart` when set). Throws RunFailure (or
/// InputError for bad input files) when the run fails; cli::run_session_process turns that
/// into the ABORT and the exit code. Removes the checkpoint when the run completes.
void run_agent(const AgentOptions& options, transport::AgentSession& session,
               std::optional<AgentCheckpoint> restart);

}  // namespace tessera::agent
