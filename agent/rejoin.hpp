#pragma once
// The agent's side of a coordinated rollback over DDS.
//
// A restarted agent (same id, finds its checkpoint) waits until its endpoints have matched
// every peer of the run, publishes REJOIN with the rounds of its checkpoint, and waits for
// the coordinator's ROLLBACK naming the round everyone resumes from. Every other agent gets
// the same ROLLBACK while blocked in its round loop (RollbackRequested), waits until its own
// endpoints have matched the restarted process (volatile messages written before that would
// be lost), moves to the new epoch and resumes from its in-memory snapshot of that round.

#include <cstdint>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <vector>

#include "runtime/checkpoint_keeper.hpp"
#include "runtime/round_loop.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// The restarted agent's hand-shake. Returns the coordinator's answer (its round is one of
/// `snapshots`' rounds). Throws transport::RunFailure on timeout or stop.
RollbackRequested request_rejoin(transport::AgentSession& session, std::uint32_t agent_id,
                                 const std::vector<ProtocolSnapshot>& snapshots, double timeout_s);

/// Every agent, before resuming after `order`: endpoints matched (bounded by `timeout_s`),
/// epoch set. Returns the snapshot to resume from; transport::RunFailure when the keeper no
/// longer holds that round.
const ProtocolSnapshot& prepare_rollback(transport::AgentSession& session,
                                         const CheckpointKeeper& keeper,
                                         const RollbackRequested& order, double timeout_s);

}  // namespace tessera::agent
