#pragma once
// Keeps a reliable writer from removing samples while one of its readers is being removed.
//
// Why: in Fast DDS 2.9.1 a VOLATILE writer drops each sample as soon as every matched reader
// acknowledged it. When a reader leaves (deleted, or its participant gone), the writer's
// StatefulWriter::matched_reader_remove takes the writer's mutex and both of its
// locator-selector locks, then re-checks acknowledgements (check_acked_status); the leaving
// reader was often the one holding samples back, so that check now removes them, and removing
// a sample that waits in the flow controller's queue (a repair, or a write whose synchronous
// send timed out) takes the flow controller's mutex. The flow controller's thread, meanwhile,
// holds that mutex while it sends queued samples; when it stops early (it cannot take the
// writer's mutex, or someone wants to remove a sample) it flushes what it last wrote for that
// writer, which takes the writer's async locator-selector lock. Each thread then waits for
// the other for good (upstream Fast-DDS PR 3468 and its successors, not in Debian's 2.9.1). The
// thread removing the reader is a receive thread holding the participant's PDP mutex, so the
// participant's discovery and liveliness stop too, and its peers lose it at its lease.
// Seen as a survivor that stopped asserting liveliness right after a refused process left
// (DdsLoss.AgentRestartedFromItsCheckpointAfterTheRepartitionIsRefused hung in 2 of 17 runs);
// stacks of the hung process in docs/dds-runtime.md. Reproduced by
// DdsWriterLockOrder.ReaderLeavingWhileItsRepairsAreQueuedDoesNotHangTheWriter: with VOLATILE
// writers 21 hangs in 700 cycles of leaving readers, with this 0 in 700 (load 11-20).
//
// A TRANSIENT_LOCAL writer never removes a sample on acknowledgement: it removes the oldest
// acknowledged one when its (bounded KEEP_ALL) history is full and a new sample is written,
// in the writing thread, which holds no locator-selector lock. The readers of the per-round
// topics stay VOLATILE, and a VOLATILE reader gets nothing a writer wrote before it matched
// (the writer sends it a GAP for its history), so what any reader receives is unchanged. Such
// a writer would keep its last history-bound samples (transport/qos.hpp,
// kVolatileWriterHistory); the writing thread drops the acknowledged ones instead
// (transport/acknowledged_drop.hpp, kDropAcknowledgedEvery).

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>

namespace tessera::transport {

/// Sets `q`'s durability to TRANSIENT_LOCAL, so that its writer removes samples only when a
/// write needs room, never while a matched reader is being removed. Readers keep their own
/// durability (VOLATILE ones receive only what is written after they matched).
void keep_acknowledged_samples(eprosima::fastdds::dds::DataWriterQos& q);

}  // namespace tessera::transport
