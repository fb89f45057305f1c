#include "transport/dds_trace.hpp"

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <ctime>

namespace tessera::transport {

DdsTrace::DdsTrace(std::string who) : who_(std::move(who)) {
  if (const char* env = std::getenv("TESSERA_DDS_TRACE"); env && *env && *env != '0') on_ = true;
}

void DdsTrace::operator()(const char* fmt, ...) const {
  if (!on_) return;
  char text[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(text, sizeof(text), fmt, args);
  va_end(args);
  const auto now = std::chrono::steady_clock::now();
  const double t = std::chrono::duration<double>(now - start_).count();
  // Also the monotonic clock itself (CLOCK_MONOTONIC, shared by every process of the host), so
  // that the logs of one run's processes merge into one timeline.
  const double mono = std::chrono::duration<double>(now.time_since_epoch()).count();
  // And this process's CPU time (all threads, CLOCK_PROCESS_CPUTIME_ID): what a step cost
  // whatever the machine's load.
  timespec cpu{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu);
  const double cpu_s = static_cast<double>(cpu.tv_sec) + 1e-9 * static_cast<double>(cpu.tv_nsec);
  std::fprintf(stderr, "[dds %8.3f @%.4f cpu %.4f %s] %s\n", t, mono, cpu_s, who_.c_str(), text);
}

}  // namespace tessera::transport
