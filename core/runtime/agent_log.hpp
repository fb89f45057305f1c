#pragma once
// The agent's phase log (--verbose): one line per phase on stderr, prefixed with the agent's
// tag so the lines of N agents sharing a terminal (tessera launch) can be told apart.

#include <time.h>

#include <cstdint>
#include <cstdio>
#include <iostream>
#include <string>

namespace tessera::agent {

/// "tessera-agent[I]": the prefix of every line an agent prints.
inline std::string agent_tag(std::uint32_t id) {
  return "tessera-agent[" + std::to_string(id) + "]";
}

struct AgentLog {
  std::string tag;  ///< agent_tag(id).
  bool verbose = false;
  /// Each line also carries the host's monotonic clock and the process's CPU time, as the DDS
  /// trace's lines do (TESSERA_DDS_TRACE=1 turns both on), so the phases fall into the merged
  /// timeline of a run's processes: "<tag> @<CLOCK_MONOTONIC s> cpu <process CPU s>: <what>".
  bool stamped = false;
  void operator()(const std::string& what) const {
    if (!verbose) return;
    if (!stamped) {
      std::cerr << tag << ": " << what << "\n";
      return;
    }
    timespec mono{}, cpu{};
    clock_gettime(CLOCK_MONOTONIC, &mono);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu);
    char stamp[96];
    std::snprintf(stamp, sizeof(stamp), " @%.4f cpu %.4f: ",
                  static_cast<double>(mono.tv_sec) + 1e-9 * static_cast<double>(mono.tv_nsec),
                  static_cast<double>(cpu.tv_sec) + 1e-9 * static_cast<double>(cpu.tv_nsec));
    std::cerr << tag << stamp << what << "\n";
  }
};

}  // namespace tessera::agent
