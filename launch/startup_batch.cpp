#include "launch/startup_batch.hpp"

#include <sched.h>

#include <mutex>

#include "launch/process_threads.hpp"

namespace tessera::launch {

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
  const sched_param normal{};
  return change_every_thread([&normal](pid_t tid) {
    return sched_getscheduler(tid) == SCHED_BATCH &&
           sched_setscheduler(tid, SCHED_OTHER, &normal) == 0;
  });
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

}  // namespace tessera::launch
