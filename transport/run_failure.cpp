#include "transport/run_failure.hpp"

#include <csignal>
#include <cstdio>

#include "transport/fastdds/shm_receive_watch.hpp"

namespace tessera::transport {

void expect_ready(WaitStatus status, const Mailroom& room, double timeout_s,
                  const std::string& what, const std::string& detail) {
  if (status == WaitStatus::kReady) return;
  if (status == WaitStatus::kStopped) {
    StopInfo stop =
        room.stop_info().value_or(StopInfo{kExitRunFailed, "stopped", false, std::nullopt, ""});
    throw RunFailure(stop.exit_code, stop.reason, !stop.remote);
  }
  char buf[64];
  std::snprintf(buf, sizeof(buf), "timed out after %g s waiting for ", timeout_s);
  const std::string stuck = shm_receive_note();
  throw RunFailure(kExitRunFailed, buf + what + (detail.empty() ? std::string() : ": " + detail) +
                                       (stuck.empty() ? std::string() : " (" + stuck + ")"));
}

std::string signal_name(int signo) {
  if (signo == SIGINT) return "SIGINT";
  if (signo == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signo);
}

}  // namespace tessera::transport
