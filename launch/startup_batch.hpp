#pragma once
// An agent forked by launch's fork server while the coordinator partitions launch's file
// starts with every thread in SCHED_BATCH and returns to SCHED_OTHER with its assignment.
//
// Why: the partition (`highest`) runs island threads that meet at a barrier after every
// epoch, on a 2-core host both cores. The agents' start-up wakes their threads a few thousand
// times meanwhile (participant creation, discovery, announcements: ~2500-2800 wake-ups of the
// 5 agents of a CSAIL run up to the partition's end), and under the kernel's wake-up
// preemption each wake-up of a normal thread may stop a partition thread on the spot; a
// stopped island then holds up the barrier for the other. Measured (docs/dds-runtime.md,
// "Start-up"): the coordinator's threads were scheduled ~3x as often as the
// in-process run's for the same partition. A SCHED_BATCH thread gets the same fair share of
// the CPU (its nice is unchanged) but its wake-ups never preempt the running thread: it runs
// when a core is free or at the next scheduler tick. Nothing is starved, so unlike
// a lower nice no bound is needed for the participant lease, and the agents' start-up CPU is
// the same: only the partition's interruptions go.
// After the assignment the round loop's latency matters again, hence the return.
//
// Switching between SCHED_OTHER and SCHED_BATCH at the same nice needs no privilege.
// Standalone tessera-agent processes (other hosts, by hand) never enter it.

#include <string>

namespace tessera::launch {

/// In a forked agent before its first thread: the calling thread to SCHED_BATCH (every thread
/// created later inherits it). Returns whether it did.
bool enter_startup_batch();

/// Every thread of this process that is in SCHED_BATCH back to SCHED_OTHER (two passes: a
/// thread created during the first by a batch thread is batch too). Idempotent and
/// thread-safe; a no-op unless enter_startup_batch() ran. Returns a one-line description for
/// --verbose ("" if nothing was done).
std::string restore_startup_batch();

}  // namespace tessera::launch
