#pragma once
// Internal: a fixed number of worker threads working through a list of independent jobs (the
// island search's islands and side jobs, the block re-split's sub-searches). Which thread runs
// which job never changes a result: every job owns its inputs and its generator.

#include <functional>
#include <vector>

namespace tessera::partition_detail {

/// CPU time of the calling thread in ms (not the process's: that adds up all threads).
double thread_cpu_ms();

/// Runs jobs[0..] on `workers` threads (the caller's one of them): each thread takes the next job
/// not yet started, so a thread whose job ends early takes on the queue's later ones. Exceptions
/// are rethrown (the lowest job's) after every thread has been joined. Returns each thread's CPU
/// time in ms (the caller's first): the largest plus the serial rest is what the wall time is on
/// an idle machine with as many cores as threads.
std::vector<double> run_jobs(const std::vector<std::function<void()>>& jobs, int workers);

}  // namespace tessera::partition_detail
