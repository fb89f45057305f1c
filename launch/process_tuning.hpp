#pragma once
// The one seam through which an agent process applies the process-level tuning of a run on one
// host (this folder): the rest of the agent calls these two functions and nothing else here.
// Both are harmless for an agent started by hand on another host.

#include <string>

namespace tessera::launch {

/// First thing in an agent process: keeps freed heap memory for the next round
/// (heap_retention.hpp) and runs OpenMP parallel regions (CHOLMOD's) on one thread
/// (serial_openmp.hpp). Process-wide.
void begin_agent_process();

/// When the agent has its assignment (the coordinator's partition is done): its threads leave the
/// start-up's SCHED_BATCH that launch's fork server gave them (startup_batch.hpp). Idempotent.
/// Returns a one-line description for --verbose, "" when nothing was changed.
std::string end_agent_startup();

}  // namespace tessera::launch
