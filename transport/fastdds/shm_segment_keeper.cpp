#include "transport/fastdds/shm_segment_keeper.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <set>
#include <sstream>

namespace tessera::transport {

namespace {

const std::string kSegmentHead = "fastrtps_";
const std::string kMarkerHead = "tessera_kept_";
const std::string kLinkHead = "tessera_link_";

// "fastrtps_<16 lowercase hex>": a participant's data segment.
bool is_segment(const std::string& name) {
  if (name.size() != kSegmentHead.size() + 16 || name.compare(0, kSegmentHead.size(), kSegmentHead))
    return false;
  return std::all_of(name.begin() + static_cast<long>(kSegmentHead.size()), name.end(),
                     [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::string hex_of(const std::string& segment) {
  return segment.substr(kSegmentHead.size());
}

// Names (in `dir`) of the files this process holds an flock on: a lock is listed in the fdinfo
// of the descriptor that holds it. Not /proc/locks, which says the same: reading it takes the
// kernel's global file-lock semaphore for writing, and the first taker waits for an RCU grace
// period (5-20 ms on a 2-core VM) while every other process's flock() waits behind it. Every
// process of a run reads this at its teardown, on the run's critical path.
std::set<std::string> files_flocked_here(const std::string& dir) {
  std::set<std::string> out;
  DIR* fds = opendir("/proc/self/fd");
  if (!fds) return out;
  const std::string own = std::to_string(dirfd(fds));
  while (dirent* e = readdir(fds)) {
    const std::string fd = e->d_name;
    if (fd == "." || fd == ".." || fd == own) continue;
    char target[PATH_MAX];
    const ssize_t n = readlink(("/proc/self/fd/" + fd).c_str(), target, sizeof(target) - 1);
    if (n <= 0) continue;
    const std::string path(target, static_cast<std::size_t>(n));
    if (path.size() <= dir.size() + 1 || path.compare(0, dir.size(), dir) != 0 ||
        path[dir.size()] != '/')
      continue;
    std::ifstream info("/proc/self/fdinfo/" + fd);
    for (std::string line; std::getline(info, line);)
      if (line.compare(0, 5, "lock:") == 0 && line.find(" FLOCK ") != std::string::npos) {
        out.insert(path.substr(dir.size() + 1));
        break;
      }
  }
  closedir(fds);
  return out;
}

// tessera_link_<pid>_<keeper>_<hex>: one per keeper, so keepers of one process that delete
// participants at the same time never share a link.
std::string link_name(const std::string& segment, unsigned long keeper) {
  return kLinkHead + std::to_string(getpid()) + "_" + std::to_string(keeper) + "_" +
         hex_of(segment);
}

std::atomic<unsigned long> next_keeper{0};

// Whether some process holds `lock`'s flock (false when the file is gone).
bool lock_held(const std::string& path) {
  const int fd = open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return false;
  const bool held = flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  close(fd);
  return held;
}

}  // namespace

std::vector<std::string> own_shm_segments(const std::string& dir) {
  std::set<std::string> mapped;
  std::ifstream maps("/proc/self/maps");
  for (std::string line; std::getline(maps, line);) {
    const auto pos = line.rfind('/');
    if (pos == std::string::npos) continue;
    const std::string name = line.substr(pos + 1);
    if (is_segment(name) && line.compare(pos - dir.size(), dir.size(), dir) == 0)
      mapped.insert(name);
  }
  const std::set<std::string> locked = files_flocked_here(dir);
  std::vector<std::string> out;
  for (const std::string& name : mapped)
    if (locked.count(name + "_el")) out.push_back(name);
  return out;
}

ShmSegmentKeeper::ShmSegmentKeeper(std::string dir)
    : dir_(std::move(dir)), id_(next_keeper.fetch_add(1)) {}

void ShmSegmentKeeper::keep() {
  for (const std::string& name : own_shm_segments(dir_)) {
    const std::string target = dir_ + "/" + link_name(name, id_);
    unlink(target.c_str());
    if (link((dir_ + "/" + name).c_str(), target.c_str()) == 0) kept_.push_back(name);
  }
}

std::vector<std::string> ShmSegmentKeeper::restore() {
  std::vector<std::string> restored;
  for (const std::string& name : kept_) {
    const std::string held = dir_ + "/" + link_name(name, id_);
    // The marker first, so a sweep never sees a restored name without one.
    const std::string marker = dir_ + "/" + kMarkerHead + hex_of(name);
    const int fd = open(marker.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd >= 0) {
      const std::string owner = std::to_string(getpid()) + "\n";
      const ssize_t written = write(fd, owner.data(), owner.size());
      (void)written;
      close(fd);
    }
    const std::string path = dir_ + "/" + name;
    if (link(held.c_str(), path.c_str()) == 0)
      restored.push_back(name);
    else if (lock_held(path + "_el"))
      unlink(marker.c_str());  // a live participant's (another one of this process)
    // else: another keeper of this process restored it meanwhile, marker included
    unlink(held.c_str());
  }
  kept_.clear();
  return restored;
}

ShmSegmentKeeper::~ShmSegmentKeeper() {
  for (const std::string& name : kept_) unlink((dir_ + "/" + link_name(name, id_)).c_str());
}

int sweep_kept_segments(const std::string& dir, double life_s, const std::vector<int>& owners) {
  std::vector<std::string> markers, links;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.compare(0, kMarkerHead.size(), kMarkerHead) == 0) markers.push_back(name);
      if (name.compare(0, kLinkHead.size(), kLinkHead) == 0) links.push_back(name);
    }
    closedir(d);
  }
  // Links of a process that ended between keep() and restore() (the teardown guard ended it).
  for (const std::string& l : links) {
    const long pid = std::strtol(l.c_str() + kLinkHead.size(), nullptr, 10);
    if (pid > 0 && kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)
      unlink((dir + "/" + l).c_str());
  }
  int removed = 0;
  const std::time_t now = std::time(nullptr);
  for (const std::string& marker : markers) {
    struct stat st {};
    if (stat((dir + "/" + marker).c_str(), &st) != 0) continue;
    if (static_cast<double>(now - st.st_mtime) < life_s) {
      if (owners.empty()) continue;
      int owner = 0;
      std::ifstream(dir + "/" + marker) >> owner;
      if (std::find(owners.begin(), owners.end(), owner) == owners.end()) continue;
    }
    const std::string segment = kSegmentHead + marker.substr(kMarkerHead.size());
    if (!is_segment(segment)) continue;
    if (lock_held(dir + "/" + segment + "_el")) continue;  // a live owner (name reused)
    if (unlink((dir + "/" + segment).c_str()) == 0) ++removed;
    unlink((dir + "/" + marker).c_str());
  }
  return removed;
}

}  // namespace tessera::transport
