#pragma once
// Dropping the acknowledged samples a writer with VOLATILE readers would otherwise keep: the
// one mechanism behind SampleWriter (the runs' per-round topics) and the online channel's pose
// blocks and statuses. Internal to transport/.

#include <cstdint>
#include <mutex>

namespace eprosima::fastdds::dds {
class DataWriter;
}

namespace tessera::transport {

/// A writer whose readers are all VOLATILE drops its acknowledged samples (DataWriter::
/// clear_history, once every sample it holds is acknowledged) after every this many writes.
/// Why: such a writer is TRANSIENT_LOCAL (fastdds/reader_removal_lock_order.hpp), so Fast DDS
/// removes an acknowledged sample only when a write needs room, and every writer kept its last
/// kVolatileWriterHistory samples for the rest of the run, sized in its topic's payload pool:
/// an agent's heap grew round after round until its pose-block and status writers held 256
/// samples each (docs/scale.md). Its readers received nothing of them: a VOLATILE reader gets
/// only what is written after it matched, and an acknowledged sample is never sent again. The
/// drop happens in the writing thread, like Fast DDS's own removal when the history is full,
/// never while a reader is being removed.
constexpr std::uint32_t kDropAcknowledgedEvery = 16;

/// The drop schedule of one writer, and the lock that makes the acknowledgement check, the drop
/// and the write one step (another thread's write between the check and the drop would remove
/// an unacknowledged sample).
class AcknowledgedDrop {
 public:
  /// Runs `write` (returns true when the sample went out) on `w` under the lock; before it,
  /// once kDropAcknowledgedEvery writes went out since the last drop, drops the writer's samples
  /// if every one is acknowledged (else tries again at the next write; readers acknowledge when
  /// a heartbeat asks, every heartbeat period). Before, not after: the sample just written is
  /// never acknowledged yet.
  template <class Write>
  bool write(eprosima::fastdds::dds::DataWriter& w, Write&& write) {
    std::lock_guard<std::mutex> lock(mutex_);
    drop_if_due(w);
    if (!write()) return false;
    ++writes_since_drop_;
    return true;
  }

 private:
  void drop_if_due(eprosima::fastdds::dds::DataWriter& w);

  std::mutex mutex_;
  std::uint32_t writes_since_drop_ = 0;
};

}  // namespace tessera::transport
