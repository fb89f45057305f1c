#pragma once
// Guards the deletion of a DDS participant at process exit.
//
// Why: Fast DDS 2.9 (Debian's libfastrtps 2.9.1, built with assertions) can fail while a
// participant is deleted, after the run's work is done and its result printed:
//  - an assertion `GUID_t::unknown() != remote_participant->m_guid` (PDP.cpp, the lease check
//    of a remote participant racing with that participant's removal) aborts the process;
//  - with DDS Security, removing a remote participant deadlocks against the same lease-check
//    timer (SecurityManager::remove_participant destroys its handshake timer while the event
//    thread waits for the PDP mutex): the process never exits.
// The abort also struck a coordinator once after its summary, while the agents' participants
// left (coordinator_run.cpp guards that step too). Both are inside Fast DDS and cannot be
// avoided from the API. While a TeardownGuard lives, a
// SIGABRT or a teardown longer than `timeout` ends the process at once with `exit_code` (the
// code the process was about to return) and a one-line note on stderr, so a finished run is
// never reported as crashed or hung.

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace tessera::transport {

class TeardownGuard {
 public:
  /// Arms the guard: `exit_code` is what the process exits with if the teardown aborts or
  /// takes longer than `timeout` (> 0); `who` names the process in the note. Only one guard
  /// may be armed at a time (the SIGABRT handler is process-wide).
  TeardownGuard(int exit_code, const std::string& who, std::chrono::duration<double> timeout);
  /// Disarms: restores the previous SIGABRT handler and stops the watchdog.
  ~TeardownGuard();
  TeardownGuard(const TeardownGuard&) = delete;
  TeardownGuard& operator=(const TeardownGuard&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread watchdog_;
};

}  // namespace tessera::transport
