#pragma once
// The DDS side of replication and take-over after a permanent agent loss (the bookkeeping is
// core/runtime/survivor_takeover.hpp; the flow is described in docs/fault-tolerance.md).

#include <cstdint>
#include <vector>

#include "runtime/survivor_takeover.hpp"
#include "tessera.h"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// Sends this agent's local problem (measurements, lifted initial poses `Y0`) to each holder
/// (hand-off messages of purpose 1).
void send_problem_replicas(transport::AgentSession& session, const AgentLocalData& local,
                           std::uint32_t self, const Eigen::MatrixXd& Y0,
                           const std::vector<std::uint32_t>& holders);

/// Moves every replica hand-off the session received into `store`.
void absorb_problem_replicas(transport::AgentSession& session, ReplicaStore& store);

/// The re-partition in `a` (epoch > 0) with the assignment before it (`old_owner`).
/// Throws transport::RunFailure when it is malformed.
Reassignment reassignment_of(const wire::PartitionAssignment& a,
                             const std::vector<std::uint32_t>& old_owner);

/// The take-over over DDS: one message to every other survivor (purpose 2, at r.epoch), waits
/// (bounded by `timeout_s`) for one from each of them, then assembles the new local problem.
/// Throws transport::RunFailure on timeout or a stopped run.
AgentLocalData exchange_takeover(transport::AgentSession& session, const TakeoverSource& src,
                                 const Reassignment& r, double timeout_s);

}  // namespace tessera::agent
