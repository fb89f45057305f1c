#include "agent/startup_batch.hpp"

#include <dirent.h>
#include <sched.h>

#include <cstdlib>
#include <mutex>

namespace tessera::agent {

namespace {

// Scheduling policy is per thread, but entering and restoring are process decisions.
struct BatchState {
  std::mutex mutex;
  bool entered = false;
};

BatchState& batch_state() {
  static BatchState state;
  return state;
}

// Every thread of this process in SCHED_BATCH to SCHED_OTHER; returns the threads changed.
int restore_threads() {
  int changed = 0;
  const sched_param normal{};
  for (int pass = 0; pass < 2; ++pass) {
    DIR* dir = opendir("/proc/self/task");
    if (!dir) return changed;
    while (dirent* e = readdir(dir)) {
      if (e->d_name[0] == '.') continue;
      const pid_t tid = static_cast<pid_t>(std::atol(e->d_name));
      if (sched_getscheduler(tid) == SCHED_BATCH &&
          sched_setscheduler(tid, SCHED_OTHER, &normal) == 0)
        ++changed;
    }
    closedir(dir);
  }
  return changed;
}

}  // namespace

bool enter_startup_batch() {
  BatchState& s = batch_state();
  std::lock_guard<std::mutex> lock(s.mutex);
  const sched_param batch{};
  s.entered = sched_setscheduler(0, SCHED_BATCH, &batch) == 0;
  return s.entered;
}

std::string restore_startup_batch() {
  BatchState& s = batch_state();
  std::lock_guard<std::mutex> lock(s.mutex);
  if (!s.entered) return "";
  s.entered = false;
  return std::to_string(restore_threads()) + " thread(s) back from SCHED_BATCH";
}

}  // namespace tessera::agent
