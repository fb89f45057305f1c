#pragma once
// Applying a per-thread setting (nice, scheduling policy) to every thread of this process.

#include <sys/types.h>

#include <functional>

namespace tessera::launch {

/// Calls `change(tid)` for every thread of this process (/proc/self/task), in two passes: a
/// thread created during the first by a thread not yet changed inherits the old setting.
/// Returns how many calls returned true.
int change_every_thread(const std::function<bool(pid_t)>& change);

}  // namespace tessera::launch
