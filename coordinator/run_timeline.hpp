#pragma once
// When each step of a distributed run ended, as the coordinator saw it: the summary's
// "timeline_ms" (milliseconds since this process started) and "started_monotonic_ms" (that
// start on the system's monotonic clock, CLOCK_MONOTONIC, which every process of the host
// shares), so a benchmark that noted the monotonic time when it launched the run can split
// the whole wall time into phases: start-up, discovery, partition, ... , shut-down
// (scripts/bench/dds_overhead.py prints that breakdown).

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "json_writer.hpp"

namespace tessera::coordinator {

class RunTimeline {
 public:
  /// Starts the clock: construct it first thing in main().
  RunTimeline() : start_(std::chrono::steady_clock::now()) {}
  /// Records that step `name` ended now (names are JSON keys; a repeated name keeps the last).
  void mark(const std::string& name) { mark_at(name, std::chrono::steady_clock::now()); }
  void mark_at(const std::string& name, std::chrono::steady_clock::time_point at) {
    const double ms = std::chrono::duration<double, std::milli>(at - start_).count();
    for (auto& [n, v] : marks_)
      if (n == name) {
        v = ms;
        return;
      }
    marks_.emplace_back(name, ms);
  }
  std::chrono::steady_clock::time_point start() const { return start_; }
  /// Process start on the monotonic clock, milliseconds (steady_clock is CLOCK_MONOTONIC).
  double started_monotonic_ms() const {
    return std::chrono::duration<double, std::milli>(start_.time_since_epoch()).count();
  }
  /// {"name": ms since start, ...} in the order marked.
  cli::JsonObject json() const {
    cli::JsonObject j;
    for (const auto& [name, ms] : marks_) j.add(name, ms);
    return j;
  }

 private:
  std::chrono::steady_clock::time_point start_;
  std::vector<std::pair<std::string, double>> marks_;
};

}  // namespace tessera::coordinator
