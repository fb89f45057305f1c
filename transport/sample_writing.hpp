#pragma once
// Writing samples: a write that finds the bounded history full (kWriterHistory unacknowledged
// samples) waits for acknowledgements and retries until SessionOptions::write_timeout_s,
// then throws TransportError; the session's counters (SessionStats). Also the bounded waits
// for acknowledgements. Internal to transport/.
//
// Except on a thread inside a NoWait scope (a listener thread running the round protocol,
// docs/dds-runtime.md "Session 12"): the acknowledgements a full history waits for may have
// to come through that very thread, so there a write tries once (Fast DDS blocks at most the
// QoS's max_blocking_time, 10 ms) and, when the history is full, goes to a backlog instead,
// with every later write until the backlog is empty (so nothing overtakes it). A waiting
// write (any other thread) writes the backlog first; the application thread is woken to do
// that (Mailroom::notify, backlogged()).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <string>

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
               const DdsTrace& trace, Mailroom& room);

  /// While one lives, this thread's writes never wait for acknowledgements (see above).
  class NoWait {
   public:
    NoWait() : outer_(active_) { active_ = true; }
    ~NoWait() { active_ = outer_; }
    NoWait(const NoWait&) = delete;
    NoWait& operator=(const NoWait&) = delete;

   private:
    bool outer_;
  };

  /// Writes `sample` on topic `topic` (retrying as above; in a NoWait scope, see above).
  /// Throws TransportError if this process has no writer for the topic, the write fails for
  /// another reason than a full history, or the history stays full past the write timeout.
  template <class T>
  void write(const std::string& topic, const T& sample) {
    if (active_) {
      std::lock_guard<std::mutex> lock(backlog_mutex_);
      if (backlog_.empty() && !flushing_ &&
          try_write_raw(topic, const_cast<T*>(&sample), serialized_size(sample)))
        return;
      defer_locked([this, topic, copy = sample]() mutable {
        write_raw(topic, &copy, serialized_size(copy));
      });
      return;
    }
    flush_backlog();
    write_raw(topic, const_cast<T*>(&sample), serialized_size(sample));
  }

  /// Whether deferred writes wait in the backlog (readable with or without the mailroom lock).
  bool backlogged() const { return backlogged_.load(); }
  /// Writes the backlog in order, waiting as write() does. Throws as write() does.
  void flush_backlog();

  /// Waits until every writer's samples are acknowledged, for at most `timeout` in total.
  void flush(Seconds timeout);
  /// Waits until the writer of `topic` (if any) has its samples acknowledged, at most
  /// `timeout` (nothing when <= 0).
  void wait_acknowledged(const std::string& topic, Seconds timeout);

  std::uint64_t bytes_sent() const { return bytes_.load(); }
  std::uint64_t messages_sent() const { return messages_.load(); }
  std::uint64_t write_retries() const { return retries_.load(); }

 private:
  void write_raw(const std::string& topic, void* sample, std::size_t bytes);
  /// One attempt: true when written; false when the history is full (`*failure`: Fast DDS's
  /// return code). Throws as write_raw for every other failure.
  bool try_write_raw(const std::string& topic, void* sample, std::size_t bytes,
                     unsigned* failure = nullptr);
  /// Appends to the backlog (requires backlog_mutex_) and wakes the mailroom's waiters.
  void defer_locked(std::function<void()> write);

  const DdsEntities& entities_;
  const SessionOptions& opt_;
  bool coordinator_;
  const DdsTrace& trace_;
  Mailroom& room_;
  std::atomic<std::uint64_t> bytes_{0}, messages_{0}, retries_{0};

  static thread_local bool active_;  // inside a NoWait scope
  std::mutex backlog_mutex_;         // guards backlog_ and flushing_; taken before the room's
  std::deque<std::function<void()>> backlog_;
  bool flushing_ = false;                // flush_backlog() writes one taken off the backlog
  std::atomic<bool> backlogged_{false};  // backlog_ not empty or flushing_; set with the room lock
  std::mutex flush_mutex_;               // one flush_backlog() at a time
};

}  // namespace tessera::transport
