#pragma once
// SIGINT / SIGTERM handling that lets a process shut down cleanly: the signals are blocked
// in every thread and received on one dedicated thread (sigwait), which calls a callback
// in ordinary thread context (typically Mailroom::request_stop, which wakes every wait).
// The main thread then deletes the DDS participant, so no shared-memory files remain.

#include <functional>
#include <thread>

namespace tessera::transport {

class SignalWatcher {
 public:
  /// Blocks SIGINT and SIGTERM for the calling thread and every thread it creates later:
  /// construct it first thing in main(), before any other thread (DDS's included) exists.
  SignalWatcher();
  /// Stops the watcher thread.
  ~SignalWatcher();
  SignalWatcher(const SignalWatcher&) = delete;
  SignalWatcher& operator=(const SignalWatcher&) = delete;

  /// Starts handling: `on_signal(signo)` runs on the watcher thread for the first SIGINT or
  /// SIGTERM; a second one terminates the process at once (exit code 128 + signo).
  void start(std::function<void(int)> on_signal);
  /// Stops the watcher thread (signals stay blocked); call before whatever the callback
  /// touches is destroyed. Idempotent.
  void stop();

 private:
  std::thread thread_;
};

/// 128 + signo, the conventional exit code after a signal.
int exit_code_for_signal(int signo);

}  // namespace tessera::transport
