#include "coordinator/coordinator_run.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "coordinator/announcement_gathering.hpp"
#include "coordinator/assignment_publishing.hpp"
#include "coordinator/file_partition.hpp"
#include "coordinator/final_merge.hpp"
#include "coordinator/loss_handling.hpp"
#include "coordinator/result_gathering.hpp"
#include "coordinator/round_reports.hpp"
#include "coordinator/run_structure.hpp"
#include "coordinator/run_summary.hpp"
#include "json_writer.hpp"
#include "robust_args.hpp"
#include "runtime/elapsed.hpp"
#include "runtime/partition_step.hpp"
#include "runtime/progress_lines.hpp"
#include "runtime/run_monitor.hpp"
#include "transport/fastdds/teardown_guard.hpp"
#include "transport/run_failure.hpp"

namespace tessera::coordinator {

using namespace tessera::transport;

namespace {
// How long the FINISHED step may run beyond its flush before the guard ends the process with
// the finished run's exit code (a Fast DDS hang there is the teardown deadlock's cousin).
constexpr double kFinishedMarginS = 5.0;
}  // namespace

void run_coordinator(const CoordinatorOptions& o, CoordinatorSession& s, RunTimeline& timeline,
                     FilePartitionJob* file_job) {
  const auto log = [&](const std::string& what) {
    if (o.verbose) std::cerr << "tessera-coordinator: " << what << "\n";
  };
  const auto t0 = std::chrono::steady_clock::now();
  timeline.mark_at("session", t0);
  // The set-up's steps as progress lines: on a large graph they take minutes before the first
  // round, which would otherwise show only the status line's "rounds -".
  const auto setup_line = [&](const std::string& what) {
    if (!o.progress) return;
    char at[32];
    std::snprintf(at, sizeof(at), "set-up %.1fs: ", ms_since(t0) / 1000.0);
    std::cout << at << what << "\n" << std::flush;
  };
  const std::uint32_t N = o.agents;

  // 1. Every agent's announcement.
  std::vector<wire::AgentAnnouncement> announcements =
      await_announcements(s, N, o.net.session.run_id, o.net.timeout_s);
  const double discovery_ms = ms_since(t0);
  timeline.mark("announced");

  // With the whole file on this host (--graph, as tessera launch runs): its partition has been
  // computed on a thread since before the session, while the participant was created and the
  // agents started and discovered us (coordinator/file_partition.hpp); what the run waits for
  // it from here on is the partition's share of the critical path.
  std::optional<FilePartition> early;
  double early_wait_ms = 0;
  if (file_job) {
    const auto wait_start = std::chrono::steady_clock::now();
    std::string why;
    std::chrono::steady_clock::time_point started, ended;
    // A stop meanwhile (signal, an agent's ABORT) ends the run now, not after the partition.
    while (!file_job->ready(std::chrono::milliseconds(50)))
      if (s.mailroom().stopped())
        expect_ready(WaitStatus::kStopped, s.mailroom(), o.net.timeout_s,
                     "the partition of " + o.graph);
    early = file_job->take(&why, &started, &ended);
    early_wait_ms =
        std::max(0.0, std::chrono::duration<double, std::milli>(ended - wait_start).count());
    timeline.mark_at("partition_start", started);
    if (early) {
      timeline.mark_at("partitioned", ended);
      log("partition of " + o.graph + " (" + o.partition + ") while the agents start: cut " +
          std::to_string(early->part.cut_edges) + " measurements in " +
          std::to_string(early->part.ms) + " ms, thread nice " +
          std::to_string(early->part.thread_nice) + " from the process's");
    } else {
      log("cannot partition " + o.graph + " early (" + why +
          "): partitioning the announced structure");
    }
  }
  const RunStructure rs = merge_announcements(announcements, N, o.net.session.run_id);
  announcements.clear();
  log("all " + std::to_string(N) + " agents announced (" +
      std::to_string(static_cast<long>(discovery_ms)) + " ms): " + std::to_string(rs.num_poses) +
      " poses, " + std::to_string(rs.num_measurements) + " measurements");
  setup_line("all " + std::to_string(N) + " agents announced: " + std::to_string(rs.num_poses) +
             " poses, " + std::to_string(rs.num_measurements) + " measurements");

  // 2. Partition (unless the file's, computed above, is this very structure) and publish the
  // assignment.
  const bool use_early = early && early->fits(rs);
  if (early && !use_early)
    log("the announced structure is not " + o.graph + "'s: partitioning the announced one");
  PartitionStepResult part = use_early ? std::move(early->part)
                                       : partition_for_agents(rs.graph, N, o.partition,
                                                              o.partition_seed, o.partition_time_s);
  early.reset();
  part.wait_ms = use_early ? early_wait_ms : early_wait_ms + part.ms;
  if (!use_early) {
    timeline.mark("partitioned");
    log("partition (" + o.partition + "): cut " + std::to_string(part.cut_edges) +
        " measurements in " + std::to_string(part.ms) + " ms");
  }
  setup_line("partition (" + o.partition + "): cut " + std::to_string(part.cut_edges) +
             " measurements in " + std::to_string(static_cast<long>(part.ms)) + " ms");
  const wire::PartitionAssignment base = make_assignment(o, rs, part);
  publish_assignment(s, base, o.certify, o.net.timeout_s);
  log("all agents ready");
  timeline.mark("ready");
  setup_line(
      "assignment sent, all agents ready: they initialise, hand off and set up their "
      "blocks until the first round");

  // 3. Final estimates (progress from round statuses meanwhile; lost agents go to the
  // arbiter, which waits for them to rejoin).
  const auto t_run = std::chrono::steady_clock::now();
  std::optional<RunMonitor> monitor;
  if (o.status_interval_s > 0)
    monitor.emplace(N, MonitorOptions{o.status_interval_s, 2, 3.0}, std::cout, t_run);
  RunMonitor* const shown = monitor ? &*monitor : nullptr;
  LossHandling losses(o, s, rs.graph, base, shown, t_run);
  RoundReports reports(o.progress, std::cout, 1000.0 * o.progress_interval_s);
  await_final_estimates(s, o, reports, losses, shown, t_run);
  const double solve_ms = ms_since(t_run);
  timeline.mark("finals");
  if (reports.results().completed_statuses > 0) {  // the rounds, as their statuses came in
    const auto at = [&](double ms) {
      return t_run + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                         std::chrono::duration<double, std::milli>(ms));
    };
    timeline.mark_at("first_status", at(reports.results().first_status_ms));
    timeline.mark_at("last_status", at(reports.results().last_status_ms));
  }

  // 4. Merge and write.
  const MergedEstimate merged = merge_final_estimates(
      s.finals().take_all(), N, losses.record().epoch, losses.record().owner, rs);
  write_merged_poses(rs, merged.poses, o.net.session.run_id, o.output, o.tum);
  timeline.mark("merged");
  if (!o.summary.empty())
    cli::write_output(
        o.summary, run_summary_json({o, rs, part, merged, reports.results(), losses.record(),
                                     s.domain(), discovery_ms, solve_ms, ms_since(t0), &timeline}));
  if (!o.rejected.empty()) {
    if (!reports.results().robust)
      throw std::runtime_error("the agents sent no robust report (no rejected set to write)");
    cli::write_rejected(o.rejected, reports.results().robust->rejected);
  }
  // The result is complete: tessera launch prints the summary on this line (kSummaryWrittenLine)
  // instead of after every process has left (FINISHED, flush, participant deletion: ~0.07 s
  // idle, several tenths under load).
  if (o.progress && !o.summary.empty()) std::cout << kSummaryWrittenLine << "\n" << std::flush;

  // 5. Tell the agents they may leave. The result is written: while the agents' participants
  // leave, Fast DDS 2.9's lease check may abort this process (transport/fastdds/teardown_guard.hpp;
  // seen once here in an idle launch), which must not turn a finished run into a crash.
  const double flush_s = std::min(3.0, o.net.timeout_s);
  const TeardownGuard finished(kExitOk, "tessera-coordinator", Seconds(flush_s + kFinishedMarginS));
  s.send_control(wire::CONTROL_FINISHED);
  s.flush(Seconds(flush_s));
  s.set_peer_loss_fatal(false);
  std::uint64_t total_bytes = 0;
  for (auto b : merged.bytes) total_bytes += b;
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "tessera-coordinator: done: %u agents, %zu poses, %u round(s), discovery %.0f ms, "
                "partition %.1f ms, %llu bytes sent by agents, %.2f s\n",
                static_cast<std::uint32_t>(losses.record().expected.size()), rs.num_poses,
                merged.rounds, discovery_ms, part.ms, static_cast<unsigned long long>(total_bytes),
                ms_since(t0) / 1000.0);
  std::cerr << buf;
}

}  // namespace tessera::coordinator
