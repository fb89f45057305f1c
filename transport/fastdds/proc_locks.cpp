#include "transport/fastdds/proc_locks.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace tessera::transport {

std::vector<ProcLock> read_proc_locks(const std::string& path) {
  std::vector<ProcLock> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string n, kind, mode, access, pid, dev;
    if (!(fields >> n >> kind)) continue;
    if (kind == "->" && !(fields >> kind)) continue;  // a waiter
    if (!(fields >> mode >> access >> pid >> dev)) continue;
    const auto colon = dev.rfind(':');
    if (colon == std::string::npos) continue;
    out.push_back(ProcLock{kind, std::strtol(pid.c_str(), nullptr, 10),
                           std::strtoul(dev.c_str() + colon + 1, nullptr, 10)});
  }
  return out;
}

}  // namespace tessera::transport
