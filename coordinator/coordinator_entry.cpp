// tessera-coordinator's body: parses the options and wires the pieces: the run's steps are
// sequenced in coordinator_run.cpp, the process life around the DDS session in
// cli/session_process.hpp.

#include "coordinator/coordinator_entry.hpp"

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "coordinator/coordinator_options.hpp"
#include "coordinator/coordinator_run.hpp"
#include "coordinator/file_partition.hpp"
#include "coordinator/run_timeline.hpp"
#include "session_process.hpp"
#include "transport/fastdds/teardown_guard.hpp"
#include "transport/signal_watcher.hpp"

namespace tessera::coordinator {

int coordinator_main(int argc, char** argv) {
  RunTimeline timeline;  // first: the summary's timeline counts from here
  transport::SignalWatcher
      signals;  // first: every thread created later inherits the blocked signals
  const std::vector<std::string> argv_list(argv + 1, argv + argc);
  CoordinatorOptions options;
  if (auto code = cli::parse_process_options(argv_list, "tessera-coordinator",
                                             cli::process_help(kCoordinatorUsage),
                                             parse_coordinator_options, options))
    return *code;
  // The graph file's partition starts now, before the participant (after SignalWatcher: its
  // thread keeps SIGINT / SIGTERM blocked), so the participant's creation and the agents'
  // start-up happen while it runs (coordinator/file_partition.hpp).
  std::unique_ptr<FilePartitionJob> file_job;
  if (!options.graph.empty())
    file_job = std::make_unique<FilePartitionJob>(options.graph, options.agents, options.partition,
                                                  options.partition_seed, options.partition_time_s,
                                                  options.partition_nice);
  const cli::ProcessRole role{"tessera-coordinator", options.net.timeout_s};
  // From the run's successful end (summary written, FINISHED sent) to the participant's
  // deletion, a Fast DDS 2.9 abort ends the process with exit code 0 and a note
  // (transport/fastdds/teardown_guard.hpp). run_coordinator's own guard covers its last step and
  // Session::close the deletion; this one also covers the step between them, where the lease
  // check's abort struck while the agents' participants left (city10000, load 16). Before the
  // flag is set an abort stays an abort.
  std::atomic<bool> delivered{false};
  const transport::TeardownGuard after_result(transport::kExitOk, "tessera-coordinator",
                                              std::chrono::seconds(0), &delivered);
  return cli::run_session_process(coordinator_session_options(options), role, signals,
                                  [&](transport::CoordinatorSession& session) {
                                    run_coordinator(options, session, timeline, file_job.get());
                                    delivered = true;
                                  });
}

}  // namespace tessera::coordinator
