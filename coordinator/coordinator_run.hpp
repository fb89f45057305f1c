#pragma once
// The steps of a distributed run on the coordinator's side, in order: gather the agents'
// announcements, partition and publish the assignment, wait for the final estimates
// (handling lost agents meanwhile), merge and write the result, tell the agents to leave.
// Each step is its own file in coordinator/; this one only sequences them.

#include "coordinator/coordinator_options.hpp"
#include "coordinator/file_partition.hpp"
#include "coordinator/run_timeline.hpp"
#include "transport/coordinator_session.hpp"

namespace tessera::coordinator {

/// Runs the whole run on an open session. Throws RunFailure (or InputError for bad
/// announcements) when the run fails; cli::run_session_process turns that into the ABORT
/// and the exit code. Marks the end of each step on `timeline` (reported in the summary).
/// `file_job`: the partition of --graph, started before the session (null without --graph).
void run_coordinator(const CoordinatorOptions& options, transport::CoordinatorSession& session,
                     RunTimeline& timeline, FilePartitionJob* file_job);

}  // namespace tessera::coordinator
