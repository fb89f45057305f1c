#pragma once
// How the agent and coordinator executables turn waits into errors: a RunFailure carries
// the exit code and the message to print, and whether the other processes should be told
// (ABORT) before leaving.

#include <stdexcept>
#include <string>

#include "transport/inbox.hpp"

namespace tessera::transport {

/// Exit codes of tessera-agent / tessera-coordinator.
constexpr int kExitOk = 0;
constexpr int kExitRunFailed = 1;  ///< Lost peer, abort, timeout, transport failure.
constexpr int kExitBadInput = 2;   ///< Bad options or input files.

class RunFailure : public std::runtime_error {
 public:
  RunFailure(int exit_code, const std::string& what, bool tell_others = true)
      : std::runtime_error(what), exit_code_(exit_code), tell_others_(tell_others) {}
  int exit_code() const { return exit_code_; }
  bool tell_others() const { return tell_others_; }

 private:
  int exit_code_;
  bool tell_others_;
};

/// Returns normally on kReady. Throws RunFailure with the stop reason on kStopped, and
/// "timed out after <timeout> s waiting for <what>[: <detail>]" on kTimeout.
void expect_ready(WaitStatus status, const Mailroom& room, double timeout_s,
                  const std::string& what, const std::string& detail = "");

/// "SIGINT", "SIGTERM" or "signal N".
std::string signal_name(int signo);

}  // namespace tessera::transport
