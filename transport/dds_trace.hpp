#pragma once
// TESSERA_DDS_TRACE=1: one timestamped stderr line per discovery, authentication, match,
// set-up message, write retry and barrier event of a session, to see where a process waits
// (docs/dds-runtime.md). Internal to transport/.

#include <chrono>
#include <string>

namespace tessera::transport {

class DdsTrace {
 public:
  /// On when TESSERA_DDS_TRACE is set and not "0". `who` (the participant name) starts every
  /// line; times are seconds since this object was made, then "@" and the monotonic clock's
  /// seconds (CLOCK_MONOTONIC, one clock for every process of the host), then "cpu" and the
  /// process's CPU seconds so far (all threads).
  explicit DdsTrace(std::string who);

  bool on() const { return on_; }
  /// Prints one line when on (truncated at 512 characters); nothing otherwise.
  void operator()(const char* fmt, ...) const __attribute__((format(printf, 2, 3)));

 private:
  bool on_ = false;
  std::string who_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace tessera::transport
