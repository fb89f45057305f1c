#pragma once
// Step 2 of a run on the coordinator's side: the partition assignment every agent receives
// (who owns which pose, the whole structure, the algorithm options) and its publication.

#include <cstdint>

#include "coordinator/coordinator_options.hpp"
#include "coordinator/run_structure.hpp"
#include "runtime/partition_step.hpp"
#include "tessera.h"
#include "transport/coordinator_session.hpp"

namespace tessera::coordinator {

/// The assignment for `part`, carrying the options the agents run with, except --certify:
/// this is also the base of the survivors' re-assignment after a permanent loss, and the
/// agents read certify from the first assignment only (publish_assignment sets it).
wire::PartitionAssignment make_assignment(const CoordinatorOptions& options,
                                          const RunStructure& structure,
                                          const PartitionStepResult& part);

/// Publishes `base` with certify = `certify`, then waits up to `timeout_s` until every
/// process of the run is ready. Throws RunFailure on a stop or the timeout (naming who is
/// missing).
void publish_assignment(transport::CoordinatorSession& session, wire::PartitionAssignment base,
                        bool certify, double timeout_s);

}  // namespace tessera::coordinator
