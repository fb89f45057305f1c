#include "runtime/phase_memory.hpp"

#include <malloc.h>

#include <cstdio>
#include <cstring>

namespace tessera::agent {

namespace {

double mb(std::uint64_t bytes) {
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

}  // namespace

PhaseMemory sample_phase_memory() {
  PhaseMemory m;
  if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    unsigned long long kb = 0;
    while (std::fgets(line, sizeof(line), f)) {
      if (std::strncmp(line, "VmRSS:", 6) == 0 && std::sscanf(line + 6, "%llu", &kb) == 1)
        m.rss = static_cast<std::uint64_t>(kb) * 1024;
      else if (std::strncmp(line, "VmHWM:", 6) == 0 && std::sscanf(line + 6, "%llu", &kb) == 1)
        m.hwm = static_cast<std::uint64_t>(kb) * 1024;
    }
    std::fclose(f);
  }
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  const struct mallinfo2 info = mallinfo2();
  m.heap_mapped = info.hblkhd;
  m.heap_in_use = info.uordblks + info.hblkhd;
  m.heap_free = info.fordblks;
  m.heap_arenas = info.arena;
#endif
  return m;
}

std::string phase_memory_line(const std::string& phase, const PhaseMemory& m) {
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "memory after %s: rss %.1f MB, hwm %.1f MB, heap in use %.1f MB (%.1f MB own "
                "maps), heap free %.1f MB",
                phase.c_str(), mb(m.rss), mb(m.hwm), mb(m.heap_in_use), mb(m.heap_mapped),
                mb(m.heap_free));
  return buf;
}

std::string phase_memory_line(const std::string& phase) {
  return phase_memory_line(phase, sample_phase_memory());
}

}  // namespace tessera::agent
