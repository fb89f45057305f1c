#pragma once
// An agent that the run has already given up on: its block was re-partitioned among the
// survivors (coordinator's loss path, docs/fault-tolerance.md) and a later assignment names
// it among `lost`. This happens to a process restarted after the re-partition (with or
// without its checkpoint), and to a live agent that the lease dropped for longer than the
// rejoin window on a busy host. Such an agent must not join again (the survivors own its
// poses now, in a new epoch) and must not take the run down either: it leaves on its own,
// with a message saying why, and sends no ABORT.

#include <cstdint>
#include <optional>
#include <string>

#include "session_process.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// The refusal: exit 1 and no ABORT (cli::LeaveAlone), the run goes on without this agent.
class LostForGood : public cli::LeaveAlone {
 public:
  LostForGood(std::uint32_t agent_id, const std::string& run_id, std::uint32_t epoch);
};

/// The epoch of `a` if it names `agent_id` among its lost agents, else nullopt.
std::optional<std::uint32_t> epoch_that_lost(const wire::PartitionAssignment& a,
                                             std::uint32_t agent_id);

/// Throws LostForGood when `a` names `agent_id` among the lost.
void refuse_if_lost(const wire::PartitionAssignment& a, std::uint32_t agent_id,
                    const std::string& run_id);

/// Looks at the assignments queued in `session` (without taking them: the caller's own
/// hand-off logic still sees them) and throws LostForGood when one names `agent_id` among
/// the lost. Assignments are kept by the coordinator's writer (transient local), so a
/// process that joins late receives every epoch's assignment shortly after matching.
void refuse_if_lost(transport::AgentSession& session, std::uint32_t agent_id);

}  // namespace tessera::agent
