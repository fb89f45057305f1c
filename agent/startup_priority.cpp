#include "agent/startup_priority.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <tessera/util/input_error.hpp>
#include <thread>

#include "agent/process_threads.hpp"

namespace tessera::agent {

void StartupPriorityOptions::validate() const {
  if (nice < 1 || nice > 19)
    throw InputError("StartupPriorityOptions.nice = " + std::to_string(nice) +
                     ": must be in 1..19");
  if (!(bound_s > 0.0 && bound_s <= 60.0))
    throw InputError("StartupPriorityOptions.bound_s = " + std::to_string(bound_s) +
                     ": must be in (0, 60]");
}

double StartupPriorityOptions::bound_for_lease(double lease_s) const {
  return std::min(bound_s, 0.4 * lease_s);
}

namespace {

// Scheduling priority is a property of the process (its threads and its group), so what was
// lowered is process state too.
struct Lowered {
  std::mutex mutex;
  bool threads = false;
  bool group = false;
};

Lowered& lowered() {
  static Lowered state;
  return state;
}

// The nice of this process's autogroup ("/autogroup-42 nice 19"); nullopt when the kernel has
// no autogroup support.
std::optional<int> autogroup_nice() {
  std::ifstream in("/proc/self/autogroup");
  std::string name, word;
  int nice = 0;
  if (in >> name >> word >> nice && word == "nice") return nice;
  return std::nullopt;
}

// Writes `nice` to /proc/self/autogroup; errno of the failure (EAGAIN: the kernel lets a
// process without CAP_SYS_ADMIN change a group's nice once per 100 ms, machine-wide), 0 if done.
int write_autogroup_nice(int nice) {
  FILE* f = std::fopen("/proc/self/autogroup", "w");
  if (!f) return errno;
  const bool put = std::fprintf(f, "%d", nice) > 0;
  int err = put ? 0 : errno;
  if (std::fclose(f) != 0 && err == 0) err = errno;  // the write reaches the kernel here
  return err;
}

// Whether a thread of this process may go back from a raised nice to 0: CAP_SYS_NICE in the
// effective set (bit 23 of CapEff), or RLIMIT_NICE >= 20 (the limit is 20 - the lowest nice).
bool can_restore_thread_nice() {
  rlimit rl{};
  if (getrlimit(RLIMIT_NICE, &rl) == 0 && (rl.rlim_cur == RLIM_INFINITY || rl.rlim_cur >= 20))
    return true;
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("CapEff:", 0) == 0) {
      const unsigned long long caps = std::strtoull(line.c_str() + 7, nullptr, 16);
      return (caps >> 23) & 1ULL;
    }
  return false;
}

// Every thread of this process to nice 0 (change_every_thread's two passes: a thread created
// meanwhile by a lowered one inherits the lowered nice). Returns the threads changed.
int restore_threads() {
  return change_every_thread([](pid_t tid) {
    errno = 0;
    const int now = getpriority(PRIO_PROCESS, static_cast<id_t>(tid));
    return errno == 0 && now != 0 && setpriority(PRIO_PROCESS, static_cast<id_t>(tid), 0) == 0;
  });
}

// The group back to nice 0, unless another agent of the group did it already; retried while
// the kernel's rate limit refuses (EAGAIN), at most ~0.3 s.
bool restore_group() {
  for (int attempt = 0; attempt < 15; ++attempt) {
    const std::optional<int> nice = autogroup_nice();
    if (!nice || *nice == 0) return true;
    const int err = write_autogroup_nice(0);
    if (err == 0) return true;
    if (err != EAGAIN) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

}  // namespace

bool lower_autogroup_nice(int nice) {
  if (!autogroup_nice()) return false;
  return write_autogroup_nice(nice) == 0 && autogroup_nice() == nice;
}

bool enter_startup_priority(const StartupPriorityOptions& o, bool autogroup) {
  o.validate();
  Lowered& l = lowered();
  std::lock_guard<std::mutex> lock(l.mutex);
  l.group = autogroup;
  l.threads = can_restore_thread_nice() && setpriority(PRIO_PROCESS, 0, o.nice) == 0;
  return l.threads || l.group;
}

bool startup_priority_lowered() {
  Lowered& l = lowered();
  std::lock_guard<std::mutex> lock(l.mutex);
  return l.threads || l.group;
}

std::string restore_startup_priority() {
  Lowered& l = lowered();
  std::lock_guard<std::mutex> lock(l.mutex);
  std::ostringstream what;
  if (l.threads) what << restore_threads() << " thread(s) back to nice 0";
  if (l.group) {
    if (l.threads) what << ", ";
    what << (restore_group()
                 ? "autogroup back to nice 0"
                 : "autogroup NOT restored (" + std::to_string(autogroup_nice().value_or(0)) + ")");
  }
  l.threads = l.group = false;
  return what.str();
}

struct StartupPriorityBound::State {
  std::mutex mutex;
  std::condition_variable cv;
  bool stop = false;
  std::thread thread;
};

StartupPriorityBound::StartupPriorityBound(double bound_s) {
  if (!startup_priority_lowered()) return;
  state_ = std::make_unique<State>();
  State* st = state_.get();
  st->thread = std::thread([st, bound_s] {
    std::unique_lock<std::mutex> lock(st->mutex);
    if (!st->cv.wait_for(lock, std::chrono::duration<double>(bound_s), [st] { return st->stop; }))
      restore_startup_priority();
  });
}

StartupPriorityBound::~StartupPriorityBound() {
  if (!state_) return;
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    state_->stop = true;
  }
  state_->cv.notify_all();
  state_->thread.join();
}

}  // namespace tessera::agent
