#include "transport/fastdds/shm_leftovers.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>

#include "transport/fastdds/rtps_ports.hpp"

namespace tessera::transport {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// "fastrtps_<16 lowercase hex>": a participant's data segment.
bool is_segment(const std::string& name) {
  const std::string head = "fastrtps_";
  if (name.size() != head.size() + 16 || name.compare(0, head.size(), head) != 0) return false;
  return std::all_of(name.begin() + static_cast<long>(head.size()), name.end(),
                     [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

// The port number of a port's file ("fastrtps_port7411", its "_el" / "_sl" lock,
// "sem.fastrtps_port7411_mutex"), or -1.
long port_of(const std::string& name) {
  std::string rest = name;
  if (rest.compare(0, 4, "sem.") == 0) {
    if (!ends_with(rest, "_mutex")) return -1;
    rest = rest.substr(4, rest.size() - 4 - 6);
  } else if (ends_with(rest, "_el") || ends_with(rest, "_sl")) {
    rest = rest.substr(0, rest.size() - 3);
  }
  const std::string head = "fastrtps_port";
  if (rest.size() <= head.size() || rest.size() > head.size() + 5 ||
      rest.compare(0, head.size(), head) != 0)
    return -1;
  const std::string digits = rest.substr(head.size());
  if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return -1;
  return std::strtol(digits.c_str(), nullptr, 10);
}

// Every file path the processes whose maps we may read map. The others are other users'
// (or the container's init): they cannot write to our files (Fast DDS creates them 0644), so
// only files we own are judged by this (owned_by_us).
std::set<std::string> mapped_by_anyone() {
  std::set<std::string> out;
  DIR* d = opendir("/proc");
  if (!d) return out;
  while (dirent* e = readdir(d)) {
    if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
    std::ifstream maps(std::string("/proc/") + e->d_name + "/maps");
    for (std::string line; std::getline(maps, line);) {
      const auto pos = line.find('/');
      if (pos != std::string::npos) out.insert(line.substr(pos));
    }
  }
  closedir(d);
  return out;
}

bool owned_by_us(const std::string& path) {
  struct stat st {};
  return stat(path.c_str(), &st) == 0 && st.st_uid == geteuid();
}

void remove_files(const std::string& dir, const std::vector<std::string>& files,
                  ShmCleanupResult& result) {
  for (const auto& f : files)
    if (unlink((dir + "/" + f).c_str()) == 0) result.removed.push_back(f);
}

// Removes `files` if nobody holds `lock` (held meanwhile, so an owner cannot take it while
// they go). False when the owner is alive.
bool remove_if_unlocked(const std::string& dir, const std::string& lock,
                        const std::vector<std::string>& files, ShmCleanupResult& result) {
  const int fd = open((dir + "/" + lock).c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return false;
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    close(fd);
    return false;
  }
  remove_files(dir, files, result);
  close(fd);
  return true;
}

}  // namespace

std::set<std::string> mapped_segments(const std::vector<pid_t>& pids) {
  std::set<std::string> out;
  for (pid_t pid : pids) {
    std::ifstream maps("/proc/" + std::to_string(pid) + "/maps");
    for (std::string line; std::getline(maps, line);) {
      const auto pos = line.rfind('/');
      if (pos == std::string::npos) continue;
      const std::string name = line.substr(pos + 1);
      if (is_segment(name)) out.insert(name);
    }
  }
  return out;
}

ShmCleanupResult remove_dead_shm_files(const ShmCleanupOptions& options) {
  ShmCleanupResult result;
  const auto lo = static_cast<long>(rtps_domain_port_base(options.domain));
  const long hi = lo + static_cast<long>(kRtpsDomainGain);
  std::set<std::string> names;
  if (DIR* d = opendir(options.dir.c_str())) {
    while (dirent* e = readdir(d)) names.insert(e->d_name);
    closedir(d);
  }
  std::map<long, std::vector<std::string>> ports;  // this domain's, with their files
  for (const auto& name : names) {
    const long port = port_of(name);
    if (port >= lo && port < hi) ports[port].push_back(name);
  }
  std::set<std::string> mapped;
  bool mapped_known = false;
  for (const auto& [number, files] : ports) {
    const std::string port = "fastrtps_port" + std::to_string(number);
    // A listener holds its port's lock file: exclusive (_el) or shared (_sl).
    std::string lock;
    for (const char* tail : {"_el", "_sl"})
      if (names.count(port + tail)) lock = port + tail;
    if (!lock.empty()) {
      if (!remove_if_unlocked(options.dir, lock, files, result)) ++result.in_use;
      continue;
    }
    // No lock file (seen after a killed run: the port and its mutex only): dead when no
    // process maps any of its files, which are ours.
    if (!mapped_known) {
      mapped = mapped_by_anyone();
      mapped_known = true;
    }
    bool used = false;
    for (const auto& f : files) {
      const std::string path = options.dir + "/" + f;
      used = used || mapped.count(path) > 0 || !owned_by_us(path);
    }
    if (used)
      ++result.in_use;
    else
      remove_files(options.dir, files, result);
  }
  for (const auto& segment : options.segments) {
    if (!is_segment(segment) || !names.count(segment + "_el")) continue;  // gone already
    if (!remove_if_unlocked(options.dir, segment + "_el", {segment, segment + "_el"}, result))
      ++result.in_use;
  }
  std::sort(result.removed.begin(), result.removed.end());
  return result;
}

}  // namespace tessera::transport
