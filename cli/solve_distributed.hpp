#pragma once
// `tessera solve GRAPH --algorithm rbcd|rbcd++|irbcd ...`: the distributed solvers, N agents
// run in one process (core/distributed/). Called by run_solve for those algorithms.

#include <chrono>
#include <string>
#include <tessera/robust/robust_options.hpp>

#include "arguments.hpp"

namespace tessera::cli {

/// Valued options and switches this command adds to `tessera solve`.
extern const char* const kDistributedValued[];
extern const char* const kDistributedSwitches[];
/// The help text of the distributed algorithms (appended to solve --help).
extern const char* kDistributedHelp;

/// With robust.kind = kGncTls the solve is GNC-TLS around the distributed solver
/// (robust/gnc_distributed.hpp) and the summary gets the robust fields.
int solve_distributed_command(const Arguments& args, const std::string& graph_path,
                              const RobustOptions& robust,
                              std::chrono::steady_clock::time_point start);

}  // namespace tessera::cli
