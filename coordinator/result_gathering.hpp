#pragma once
// Step 3 of a run on the coordinator's side: the wait for every agent's final estimate.
// Meanwhile the round statuses feed the progress lines, the operator's status monitor and
// the lost-agent handling, which the session is polled for a few times a second.

#include <chrono>

#include "coordinator/coordinator_options.hpp"
#include "coordinator/loss_handling.hpp"
#include "coordinator/round_reports.hpp"
#include "runtime/run_monitor.hpp"
#include "transport/coordinator_session.hpp"

namespace tessera::coordinator {

/// Returns once agent 0's final report and the final estimate of every expected agent (of
/// the current epoch) are queued in session.finals(). Throws RunFailure on a stop, on
/// --run-timeout (counted from `t_run`, naming the agents whose estimates are missing), or
/// when `losses` decides the run cannot go on. `monitor` may be null.
void await_final_estimates(transport::CoordinatorSession& session,
                           const CoordinatorOptions& options, RoundReports& reports,
                           LossHandling& losses, RunMonitor* monitor,
                           std::chrono::steady_clock::time_point t_run);

}  // namespace tessera::coordinator
