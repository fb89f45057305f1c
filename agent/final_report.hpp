#pragma once
// Step 8 of a run on the agent's side: the final estimate to the coordinator, and the wait
// for its FINISHED (it has the merged result). Until then the run is not over: a rollback
// (another agent rejoined) or a re-partition (an agent was lost for good) means doing the
// rounds again, so those orders are raised to the run loop.

#include <chrono>

#include "agent/agent_options.hpp"
#include "runtime/agent_log.hpp"
#include "runtime/round_loop.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// Writes --output, publishes `result` as this agent's final estimate and waits for the
/// coordinator's FINISHED (bounded by --timeout), then prints the "done" line (times counted
/// from `t0`). Throws RollbackRequested or RepartitionRequested when ordered meanwhile, and
/// RunFailure on a stop, a timeout or a result that does not match `local`.
void deliver_final_estimate(transport::AgentSession& session, const AgentLocalData& local,
                            const RoundLoopResult& result, const AgentOptions& options,
                            const AgentLog& log, std::chrono::steady_clock::time_point t0);

}  // namespace tessera::agent
