#pragma once
// launch(): one distributed solve on this host as separate processes, the coordinator and N
// agents talking over DDS (tessera-coordinator and tessera-agent, found next to the running
// executable, started through tessera-fork-server when it is there). `tessera launch` is
// parse_launch_options() + launch().

#include <string>
#include <vector>

#include "launch/launch_options.hpp"

namespace tessera::launch {

struct LaunchResult {
  /// 0 done, 1 the run failed (a process failed, or the time limit), 130 interrupted.
  int exit_code = 0;
  std::string run_id;
  /// Why the run failed ("" when exit_code is 0).
  std::string failure;
  /// The coordinator's JSON summary ("" when none was written).
  std::string summary_json;
  /// Processes lost during the run that the run went on without ("agent 2").
  std::vector<std::string> lost;
  /// Notes of the processes' logs (e.g. a Fast DDS abort covered at the end of the run).
  std::vector<std::string> notes;
  /// Seconds from the processes' start to the end of the run.
  double wall_s = 0;

  /// A few lines for people: outcome, run id, wall time, losses and notes.
  std::string full_report() const;
};

/// Validates `options` (InputError naming the bad field), starts every process, streams the
/// coordinator's progress and the summary to stdout, and takes everything down on the first
/// failure, on the time limit and on SIGINT / SIGTERM. Throws InputError for bad input (missing
/// executables or graph files), std::runtime_error when the processes cannot be started.
LaunchResult launch(LaunchOptions options);

}  // namespace tessera::launch
