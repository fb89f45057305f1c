#pragma once
// Watching a launch run's processes once they are started: streams the coordinator's progress,
// judges every process's end (launch_loss_policy.hpp), and stops the run on the first failure,
// the time limit or a signal.

#include <signal.h>

#include <chrono>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "launch/launch_children.hpp"
#include "launch/launch_loss_policy.hpp"

namespace tessera::launch {

/// While alive, SIGINT and SIGTERM are noted (stop_requested()) instead of ending launch, so a
/// Ctrl-C stops the children cleanly instead of orphaning them. One at a time per process.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  /// The signal received (SIGINT or SIGTERM), 0 if none.
  static int stop_requested();

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

struct SupervisionOptions {
  int progress_fd = -1;    ///< read end of the coordinator's stdout (closed by supervise())
  std::string summary;     ///< the coordinator's JSON summary file
  bool quiet = false;      ///< no progress lines
  double timeout_s = 600;  ///< time limit of the run, counted from `start`
  std::chrono::steady_clock::time_point start;
  LaunchLossOptions loss;
};

struct SupervisionOutcome {
  std::string failure;  ///< why the run failed; "" when it did not
  int exit_code = 0;    ///< 0, 1 (failed), 2 (bad input: failure_report.hpp) or 130 (interrupted)
  /// The summary was read and printed (once the coordinator said it was written).
  bool summary_printed = false;
  std::string summary;  ///< its text
  /// A process ended through a teardown guard (a note in its log).
  bool guard_ended = false;
  /// Data segments the run's processes mapped when one of them failed
  /// (transport/fastdds/shm_leftovers.hpp).
  std::set<std::string> run_segments;
};

/// Runs until every process has ended or the run fails; on failure every process is stopped
/// (given 3 s to stop on its own, then SIGINT, then SIGKILL) and the failed ones' log tails are
/// printed. Prints progress lines and the summary on stdout as they come.
SupervisionOutcome supervise(std::vector<Child>& children, const SupervisionOptions& o);

/// The summary file's text, nullopt when it cannot be read.
std::optional<std::string> read_summary(const std::string& path);

/// Prints the coordinator's JSON summary (launch's main output).
void print_summary(const std::string& text);

}  // namespace tessera::launch
