#pragma once
// Fast DDS shared-memory files that a run's killed processes leave in /dev/shm.
//
// Why: Fast DDS 2.9 removes a process's shared-memory files only when that process deletes its
// participant; one that is SIGKILLed or aborts leaves its listening ports (fastrtps_port<N>,
// the lock fastrtps_port<N>_el or _sl, sem.fastrtps_port<N>_mutex) and its data segment
// (fastrtps_<hex>, lock fastrtps_<hex>_el) behind, and dead ports kept every later run on
// that domain from discovering its peers until they were removed. A live owner holds the lock file
// (flock), so a lock nobody holds marks a dead owner's files; a port whose lock file is gone (seen:
// the port and its mutex only) is dead when no process maps it. `fastdds shm clean` looks at lock
// files only, and at every domain. `tessera launch` (launch/run_cleanup.hpp) removes before each
// run, and after a run that lost a process, the dead ports of its own domain (RTPS's default ports:
// 7400 + 250 domain, up to the next domain's) and the dead segments its own processes had mapped --
// never a file whose lock is held or that a process maps, never another domain's port, never
// a segment no process of the run used. (A process that has just created a port but not yet
// locked or mapped it could lose it: a run of its own domain starting in that instant;
// launch's domain is its run's.) No Fast DDS types: compiled into launch/'s library, which
// does not link Fast DDS.

#include <sys/types.h>

#include <set>
#include <string>
#include <vector>

namespace tessera::transport {

struct ShmCleanupOptions {
  int domain = 0;
  /// Data segments (fastrtps_<hex>) that may be removed when dead (mapped_segments()).
  std::set<std::string> segments;
  std::string dir = "/dev/shm";
};

struct ShmCleanupResult {
  std::vector<std::string> removed;  ///< File names, sorted.
  std::size_t in_use = 0;            ///< Ports and segments of the options skipped: owner alive.
};

/// The data segments (fastrtps_<hex>, not ports) that the live processes `pids` map now.
std::set<std::string> mapped_segments(const std::vector<pid_t>& pids);

/// Removes the domain's dead ports and the listed segments whose lock no process holds.
ShmCleanupResult remove_dead_shm_files(const ShmCleanupOptions& options);

}  // namespace tessera::transport
