#include "coordinator/partition_priority.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

namespace tessera::coordinator {

int lower_partition_thread_nice(int offset) {
  if (offset >= 0) return 0;
  // On Linux, PRIO_PROCESS with a thread id sets that thread's nice alone.
  const auto tid = static_cast<id_t>(syscall(SYS_gettid));
  errno = 0;
  const int before = getpriority(PRIO_PROCESS, tid);
  if (errno != 0) return 0;
  const int target = std::max(-20, before + offset);
  if (target == before || setpriority(PRIO_PROCESS, tid, target) != 0) return 0;
  return target - before;
}

}  // namespace tessera::coordinator
