#pragma once
// Wall time since a moment, in the unit the coordinator reports (milliseconds in the
// summary's *_ms fields and the log lines).

#include <chrono>

namespace tessera::coordinator {

inline double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace tessera::coordinator
