#include "launch/free_domain.hpp"

#include <dirent.h>
#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include "transport/fastdds/proc_locks.hpp"
#include "transport/fastdds/rtps_ports.hpp"
#include "transport/run_identity.hpp"

namespace tessera::launch {

namespace {

// Inodes of every file some process holds a lock on.
std::set<unsigned long> locked_inodes(const std::string& locks) {
  std::set<unsigned long> out;
  for (const transport::ProcLock& lock : transport::read_proc_locks(locks)) out.insert(lock.inode);
  return out;
}

bool shm_port_locked(long lo, long hi, const DomainProbe& probe) {
  const std::set<unsigned long> locked = locked_inodes(probe.locks);
  if (locked.empty()) return false;
  DIR* d = opendir(probe.shm_dir.c_str());
  if (!d) return false;
  bool live = false;
  const std::string head = "fastrtps_port";
  while (dirent* e = readdir(d)) {
    const std::string name = e->d_name;
    if (name.size() < head.size() + 4 || name.compare(0, head.size(), head) != 0) continue;
    const std::string tail = name.substr(name.size() - 3);
    if (tail != "_el" && tail != "_sl") continue;
    const long port = std::strtol(name.c_str() + head.size(), nullptr, 10);
    if (port < lo || port >= hi) continue;
    struct stat st {};
    if (stat((probe.shm_dir + "/" + name).c_str(), &st) == 0 && locked.count(st.st_ino)) {
      live = true;
      break;
    }
  }
  closedir(d);
  return live;
}

// /proc/net/udp: "sl local_address:port(hex) ...".
bool udp_port_bound(long port, const DomainProbe& probe) {
  std::ifstream in(probe.udp);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string sl, local;
    if (!(fields >> sl >> local)) continue;
    const auto colon = local.rfind(':');
    if (colon == std::string::npos) continue;
    if (std::strtol(local.c_str() + colon + 1, nullptr, 16) == port) return true;
  }
  return false;
}

}  // namespace

bool domain_in_use(int domain, const DomainProbe& probe) {
  const auto lo = static_cast<long>(transport::rtps_domain_port_base(domain));
  return udp_port_bound(lo, probe) ||
         shm_port_locked(lo, lo + static_cast<long>(transport::kRtpsDomainGain), probe);
}

int free_domain_from(int first, const DomainProbe& probe) {
  int d = first;
  for (int tried = 0; tried < transport::kMaxDomain; ++tried) {
    if (!domain_in_use(d, probe)) return d;
    d = d % transport::kMaxDomain + 1;  // 1..kMaxDomain, as domain_for_run
  }
  return first;
}

}  // namespace tessera::launch
