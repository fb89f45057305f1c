#pragma once
// Writing samples: a write that finds the bounded history full (kWriterHistory unacknowledged
// samples) waits for acknowledgements and retries until SessionOptions::write_timeout_s,
// then throws TransportError; the session's counters (SessionStats). Also the bounded waits
// for acknowledgements, and dropping the acknowledged samples a writer with VOLATILE readers
// would otherwise keep (acknowledged_drop.hpp). Internal to transport/.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "transport/acknowledged_drop.hpp"
#include "transport/dds_entities.hpp"
#include "transport/dds_trace.hpp"
#include "transport/inbox.hpp"
#include "transport/message_mapping.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport {

class SampleWriter {
 public:
  /// `coordinator`: the role named in the error for a topic this process does not write.
  SampleWriter(const DdsEntities& entities, const SessionOptions& options, bool coordinator,
               const DdsTrace& trace);

  /// Writes `sample` on topic `topic` (retrying as above). Throws TransportError if this
  /// process has no writer for the topic, the write fails for another reason than a full
  /// history, or the history stays full past the write timeout.
  /// `timeout_s` > 0 replaces the write timeout for this write (a step whose receivers may be
  /// busy computing for longer; a dead one frees the history when its lease expires).
  template <class T>
  void write(const std::string& topic, const T& sample, double timeout_s = 0) {
    write_raw(topic, const_cast<T*>(&sample), serialized_size(sample), timeout_s);
  }

  /// Waits until every writer's samples are acknowledged, for at most `timeout` in total.
  void flush(Seconds timeout);
  /// Waits until the writer of `topic` (if any) has its samples acknowledged, at most
  /// `timeout` (nothing when <= 0). True when every matched reader acknowledged them.
  bool wait_acknowledged(const std::string& topic, Seconds timeout);

  std::uint64_t bytes_sent() const { return bytes_.load(); }
  std::uint64_t messages_sent() const { return messages_.load(); }
  std::uint64_t write_retries() const { return retries_.load(); }

 private:
  void write_raw(const std::string& topic, void* sample, std::size_t bytes, double timeout_s);
  // The write with its retries while the history is full; throws TransportError at the bound.
  void write_retrying(eprosima::fastdds::dds::DataWriter& w, const std::string& topic, void* sample,
                      std::size_t bytes, double timeout_s);
  // The drop schedule of a topic whose readers are VOLATILE (made at its first write).
  AcknowledgedDrop& drop_of(const std::string& topic);

  const DdsEntities& entities_;
  const SessionOptions& opt_;
  bool coordinator_;
  const DdsTrace& trace_;
  std::atomic<std::uint64_t> bytes_{0}, messages_{0}, retries_{0};
  std::mutex drops_mutex_;
  std::map<std::string, std::unique_ptr<AcknowledgedDrop>> drops_;
};

}  // namespace tessera::transport
