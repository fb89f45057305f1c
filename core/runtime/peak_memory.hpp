#pragma once
// The process's peak resident set (the kernel's VmHWM), which each agent reports with its final
// estimate so that a run's memory is visible in its summary. It counts every page the process
// ever had resident at once, including pages it shares copy-on-write with the fork server (a
// preloaded graph) or with Fast DDS's shared-memory segments: an upper bound of what the process
// alone costs.

#include <cstdint>

namespace tessera::agent {

/// Peak resident set size of this process in bytes (VmHWM from /proc/self/status, else
/// getrusage's ru_maxrss); 0 when neither is available.
std::uint64_t peak_resident_bytes();

}  // namespace tessera::agent
