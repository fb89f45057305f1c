#include "runtime/peak_memory.hpp"

#include <sys/resource.h>

#include <cstdio>
#include <cstring>

namespace tessera::agent {

std::uint64_t peak_resident_bytes() {
  if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    unsigned long long kb = 0;
    bool found = false;
    while (std::fgets(line, sizeof(line), f))
      if (std::strncmp(line, "VmHWM:", 6) == 0) {
        found = std::sscanf(line + 6, "%llu", &kb) == 1;
        break;
      }
    std::fclose(f);
    if (found) return static_cast<std::uint64_t>(kb) * 1024;
  }
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) == 0 && u.ru_maxrss > 0)
    return static_cast<std::uint64_t>(u.ru_maxrss) * 1024;  // Linux reports kilobytes
  return 0;
}

}  // namespace tessera::agent
