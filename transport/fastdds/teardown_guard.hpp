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
// left (coordinator_run.cpp guards that step too), and an agent at the end of a run
// (cli/session_process.cpp covers an agent from the coordinator's FINISHED on). Both are
// inside Fast DDS and cannot be avoided from the API. While a TeardownGuard lives, a
// SIGABRT or a teardown longer than `timeout` ends the process at once with `exit_code` (the
// code the process was about to return) and a one-line note on stderr, so a finished run is
// never reported as crashed or hung.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

namespace tessera::transport {

class TeardownGuard {
 public:
  /// Arms the guard: `exit_code` is what the process exits with if the teardown aborts or
  /// takes longer than `timeout` (0: no time bound, aborts only); `who` names the process in
  /// the note. With `only_once`, an abort is covered only once *only_once is true (set by
  /// another thread when the process's result is delivered; it must outlive the guard);
  /// before, it stays an abort (a real failure must not be hidden). Guards nest: an inner one
  /// (e.g. the participant's deletion) takes over until it is destroyed, then the outer one
  /// holds again.
  TeardownGuard(int exit_code, const std::string& who, std::chrono::duration<double> timeout,
                const std::atomic<bool>* only_once = nullptr);
  /// Disarms: stops the watchdog and restores what was armed before (the outer guard's cover
  /// or the previous SIGABRT handler).
  ~TeardownGuard();
  TeardownGuard(const TeardownGuard&) = delete;
  TeardownGuard& operator=(const TeardownGuard&) = delete;

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread watchdog_;
  // The outer guard's state, restored by the destructor.
  int previous_exit_code_ = 1;
  std::string previous_note_;
  const std::atomic<bool>* previous_only_once_ = nullptr;
  bool previous_was_guard_ = false;
};

}  // namespace tessera::transport
