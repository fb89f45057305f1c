#pragma once
// The priority of the thread that partitions launch's graph file while the agents start
// (file_partition.hpp): the one place where the coordinator asks the kernel for more than a
// fair share of the cores.
//
// Why it exists: on 2 cores the thread shares them with the run's own start-up (the
// coordinator's participant, the fork server, the agents' participants; the agents are in
// SCHED_BATCH, launch/startup_batch.hpp, which stops their wake-ups from preempting it but not
// their fair share), so the demo's 6.5 ms partition took 6-100 ms of wall. At a lower nice
// the scheduler gives it most of a core while it runs. The start-up it then delays is on the
// run's critical path and the hidden partition is not, so it is off by default: paired
// launches measured a shorter partition but no shorter run (docs/decisions.md).
//
// Lowering a nice needs CAP_SYS_NICE (e.g. root) or an RLIMIT_NICE that allows it; without
// them the thread keeps its nice. Nice weighs threads within one autogroup (the run's session,
// when the kernel groups by session): it takes no CPU from other sessions. Threads the
// partitioner starts (the island searches of `strong` / `highest`) inherit it.

namespace tessera::coordinator {

/// Moves the calling thread's nice by `offset` (-20..0; 0 = leave it) from its own, so that a run
/// started under `nice -n K` keeps its place among the user's processes (a nice below -20 is -20).
/// Returns the change it got: `offset` (less when clamped), 0 when the kernel refused.
int lower_partition_thread_nice(int offset);

}  // namespace tessera::coordinator
