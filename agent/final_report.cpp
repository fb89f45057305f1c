#include "agent/final_report.hpp"

#include <cstdio>
#include <iostream>
#include <string>
#include <tessera/graph/flat_pose.hpp>

#include "agent/dds_channel.hpp"
#include "agent/test_abort_hook.hpp"
#include "runtime/local_dump.hpp"
#include "runtime/peak_memory.hpp"
#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"

namespace tessera::agent {

using namespace tessera::transport;

void deliver_final_estimate(AgentSession& s, const AgentLocalData& local,
                            const RoundLoopResult& result, const AgentOptions& o,
                            const AgentLog& log, std::chrono::steady_clock::time_point t0) {
  Mailroom& room = s.mailroom();
  if (result.poses.size() != local.owned.size())
    throw RunFailure(kExitRunFailed, "the round loop returned " +
                                         std::to_string(result.poses.size()) + " poses for " +
                                         std::to_string(local.owned.size()) + " owned poses");
  {
    char line[320];
    std::snprintf(line, sizeof(line),
                  "round loop done: %u round(s) in %.3f s, rounding %.3f s (%u CG iterations, "
                  "%u message steps); of both: waiting %.3f s, sending %.3f s; %llu messages "
                  "sent, %llu protocol messages received, %llu write retries",
                  result.rounds, result.solve_s, result.rounding_s, result.translation_iterations,
                  result.rounding_steps, result.wait_s, result.send_s,
                  static_cast<unsigned long long>(s.stats().messages_sent),
                  static_cast<unsigned long long>(s.stats().protocol_samples_received),
                  static_cast<unsigned long long>(s.stats().write_retries));
    log(line);
  }
  if (result.refine_wall_s > 0 || result.certificate_wall_s > 0) {
    char line[200];
    std::snprintf(line, sizeof(line),
                  "after the rounds: refinement %.3f s (waiting %.3f s), certificate %.3f s "
                  "(waiting %.3f s)",
                  result.refine_wall_s, result.refine_wait_s, result.certificate_wall_s,
                  result.certificate_wait_s);
    log(line);
  }
  for (const NewtonRefineResult& r : result.refines) {
    const NewtonRefineTimes& t = r.times;
    char line[400];
    std::snprintf(line, sizeof(line),
                  "refinement: %.3f s wall, %.3f CPU-s: set-up %.3f, factors %.3f, Sigma %.3f, "
                  "CG %.3f, trial points %.3f, translations %.3f; Sigma factored %d, taken from "
                  "agent 0 %d; trial block factors unused %d",
                  t.wall_s, t.cpu_s, t.setup_s, t.factor_s, t.sigma_s, t.cg_s, t.trial_s,
                  t.translations_s, r.sigma_factorizations, r.sigma_imports,
                  r.pending_factors_unused);
    log(line);
  }
  if (!o.output.empty()) write_vertices_g2o(local.owned, result.poses, local.d, o.output);

  test_hold_point(o.id);
  test_abort_point(TestAbortPoint::kBeforeResult, o.id);
  wire::FinalEstimate fin;
  fin.run_id(o.net.session.run_id);
  fin.sender(o.id);
  fin.dim(static_cast<std::uint32_t>(local.d));
  fin.rounds(result.rounds);
  fin.pose_ids(local.owned);
  for (const Pose& p : result.poses) append_flat_pose(fin.pose_data(), p);
  fin.bytes_sent(s.stats().bytes_sent + serialized_size(fin));
  fin.epoch(s.epoch());
  fin.peak_rss_bytes(peak_resident_bytes());
  s.publish(fin);
  // Until FINISHED, a rollback (another agent rejoined) means doing the rounds again.
  const auto wait_start = std::chrono::steady_clock::now();
  for (;;) {
    const WaitStatus st = s.wait_finished(Seconds(0.2));
    if (st == WaitStatus::kReady) break;
    if (auto order = take_rollback(s)) throw *order;
    if (auto a = take_reassignment(s)) throw RepartitionRequested(std::move(*a));
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wait_start).count();
    if (st == WaitStatus::kStopped || waited > o.net.timeout_s)
      expect_ready(st, room, o.net.timeout_s, "the coordinator to confirm the merged result");
  }
  s.set_peer_loss_fatal(false);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "%s: done: %zu poses, %zu measurements, %u round(s), cost %.12g, %llu bytes "
                "sent, %.2f s\n",
                log.tag.c_str(), local.owned.size(), local.measurements.size(), result.rounds,
                result.cost, static_cast<unsigned long long>(s.stats().bytes_sent), secs);
  std::cerr << buf;
  // From here on the run is complete (cli/session_process.cpp covers an abort, e.g. Fast DDS's
  // lease check while the others' participants leave).
  test_abort_point(TestAbortPoint::kAfterFinished, o.id);
}

}  // namespace tessera::agent
