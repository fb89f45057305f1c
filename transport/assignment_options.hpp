#pragma once
// The algorithm options of a run in the coordinator's assignment (wire::PartitionAssignment):
// the one place where each of them meets its IDL field, both ways. The coordinator writes them
// once, every agent reads them back, so every agent of the run solves with the same options
// (the run-wide ones that change the arithmetic, like --tangent-dots or the GNC schedule,
// cannot differ between agents).

#include "runtime/round_loop.hpp"
#include "tessera.h"

namespace tessera::transport {

/// Writes `options` into `asg`'s option fields: algorithm, initialization, rank, rounds,
/// tolerances, seed, certify, coarse, refinement, tangent dots, and (only when
/// options.robust.kind is not none; a plain run's assignment keeps the robust fields' wire
/// defaults) the robust fields. max_factor_entries is not written: each agent sets its host's
/// (runtime/team_memory.hpp). The assignment's other fields (owner, structure, loss handling)
/// are left as they are.
void write_run_options(const agent::RunOptions& options, wire::PartitionAssignment& asg);

/// The options `asg` carries (write_run_options' inverse; max_factor_entries 0). An empty
/// string field stands for core's default. Throws InputError naming the field when a value is
/// not one the agents know (an unknown robust kind, mu hold or probe cut, or RobustOptions that
/// fail validate()).
agent::RunOptions run_options_of(const wire::PartitionAssignment& asg);

}  // namespace tessera::transport
