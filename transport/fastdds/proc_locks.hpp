#pragma once
// The file locks the kernel lists in /proc/locks. Fast DDS 2.9 marks a live shared-memory
// segment or port by holding a lock on its "_el"/"_sl" file, so a lock tells a live owner from
// a dead one (launch/free_domain.hpp). No Fast DDS types.

#include <string>
#include <vector>

namespace tessera::transport {

struct ProcLock {
  std::string kind;  ///< FLOCK, POSIX, OFDLCK
  long pid = 0;      ///< the holder (or the waiter, for a "->" line)
  unsigned long inode = 0;
};

/// Every line of `path` ("N: [->] KIND MODE ACCESS PID MAJ:MIN:INODE START END"); lines it
/// cannot read are skipped, a missing file gives none.
std::vector<ProcLock> read_proc_locks(const std::string& path = "/proc/locks");

}  // namespace tessera::transport
