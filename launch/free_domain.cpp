#include "launch/free_domain.hpp"

#include <dirent.h>
#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include "transport/run_identity.hpp"

namespace tessera::launch {

namespace {

constexpr long kPortBase = 7400, kDomainGain = 250;  // RTPS's default port mapping

// Inodes of every file some process holds a lock on ("N: FLOCK ADVISORY WRITE PID MAJ:MIN:INODE
// START END"; a waiter's line has "->" after the number).
std::set<unsigned long> locked_inodes(const std::string& locks) {
  std::set<unsigned long> out;
  std::ifstream in(locks);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string n, kind, mode, access, pid, dev;
    if (!(fields >> n >> kind)) continue;
    if (kind == "->" && !(fields >> kind)) continue;
    if (!(fields >> mode >> access >> pid >> dev)) continue;
    const auto colon = dev.rfind(':');
    if (colon != std::string::npos) out.insert(std::strtoul(dev.c_str() + colon + 1, nullptr, 10));
  }
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
  const long lo = kPortBase + kDomainGain * domain;
  return udp_port_bound(lo, probe) || shm_port_locked(lo, lo + kDomainGain, probe);
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
