#include "agent/agent_run.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <thread>

#include "agent/agent_gate.hpp"
#include "agent/block_replication.hpp"
#include "agent/dds_channel.hpp"
#include "agent/final_report.hpp"
#include "agent/lost_for_good.hpp"
#include "agent/rejoin.hpp"
#include "agent/run_setup.hpp"
#include "agent/test_abort_hook.hpp"
#include "launch/heap_retention.hpp"
#include "runtime/agent_log.hpp"
#include "runtime/checkpoint_keeper.hpp"
#include "runtime/phase_memory.hpp"
#include "runtime/round_loop.hpp"
#include "transport/run_failure.hpp"

namespace tessera::agent {

using namespace tessera::transport;

namespace {

// Step 7: THE SEAM, core's round protocol over DDS, until the coordinator confirms the
// merged result (step 8, inside the loop: an order while waiting for it repeats the rounds).
// `local` is the block of the first epoch (fresh or from the checkpoint).
void solve(AgentSession& s, const AgentOptions& o, const AgentLog& log, const AgentLocalData& local,
           const std::optional<AgentCheckpoint>& restart, const RunSetup* setup,
           std::chrono::steady_clock::time_point t0) {
  const bool rejoin_enabled = setup && setup->rejoin_enabled;
  BlockReplication replication(s, o.id, setup ? setup->replicas : 0,
                               setup ? setup->replica_every : 10, log);
  DdsProtocolChannel channel(s);
  CheckpointKeeper keeper(o.net.session.run_id, local, {o.checkpoint_dir, o.checkpoint_every});
  std::optional<ProtocolSnapshot> from;  // a copy: the keeper replaces its entries
  // With a rejoin window (or replicas) the coordinator arbitrates lost agents (it waits for a
  // restart, then orders a rollback or a re-partition, or gives up and aborts the run): do not
  // stop on one.
  const bool arbitrated = rejoin_enabled || restart || replication.enabled();
  if (arbitrated) s.set_agent_loss_tolerated(true);
  // Round statuses through the relay agent when the coordinator asks for it
  // (transport/status_relay.hpp: 2N - 1 deliveries a step instead of N^2), but never while
  // lost agents are arbitrated: the rejoin arbiter picks the rollback round from each agent's
  // own last status, which a relay waiting for a dead agent (or dead itself) would hold back.
  // Every agent reads the same assignment, so all choose alike.
  RoundTraffic traffic;
  traffic.status_relay = setup && setup->status_relay && !arbitrated;
  // The coordinator reads each round's statuses only while it arbitrates lost agents (the
  // rollback round is the newest every agent has sent its status for); otherwise it follows
  // the agents' progress digests, a few a second (agent/progress_digest.hpp).
  traffic.coordinator_follows_rounds = arbitrated;
  s.set_round_traffic(traffic);
  if (!arbitrated) channel.report_progress(o.id, local.num_agents);
  const AgentLocalData* cur = &local;  // the survivors' new block after a re-partition
  if (replication.enabled() && !restart) replication.start(local, channel, o.net.timeout_s);
  if (restart) {
    keeper.adopt(restart->snapshots);
    // Secured: the restarted process's handshakes may stall like a fresh one's; the gate
    // re-creates its participant if so (nothing was sent yet, so peers just forget the old
    // one), and meanwhile looks for the assignment that says the run went on without it.
    if (!s.options().security_dir.empty()) {
      pass_agent_gate(
          s, o, [&] { refuse_if_lost(s, o.id); }, /*joining=*/true);
      log(std::string("peers known") + s.options().transports_note());
    }
    const RollbackRequested order = request_rejoin(s, o.id, restart->snapshots, o.net.timeout_s);
    from = prepare_rollback(s, keeper, order, o.net.timeout_s);
    log("rejoined: resuming at round " + std::to_string(order.round) + ", epoch " +
        std::to_string(order.epoch));
  }
  RoundLoopHooks hooks;
  SnapshotReaders readers;
  readers.rejoin = rejoin_enabled;
  readers.restarted = restart.has_value();
  readers.checkpoint_files = !o.checkpoint_dir.empty();
  readers.replicas = replication.enabled();
  if (snapshots_needed(readers))
    hooks.on_round = [&](const ProtocolSnapshot& snap) {
      if (cur == &local) keeper.on_round(snap);
      if (replication.enabled()) replication.on_round(*cur, snap);
    };
  // The block set-up's temporaries (the factors' analyses, the matrices they were built from)
  // would otherwise stay under the rounds as free heap: 70 MB on a 16,000-pose 3D block.
  hooks.after_set_up = [] { launch::release_freed_heap(); };
  if (test_kill_armed())  // test builds only (agent/test_abort_hook.hpp)
    hooks.on_progress_point = [&](ProgressStage stage) { test_kill_point(stage, o.id); };
  if (log.verbose)
    hooks.on_phase = [&](const std::string& phase) { log(phase_memory_line(phase)); };
  log(std::string("round snapshots: ") +
      (hooks.on_round ? "kept (rejoin, checkpoints or replicas)" : "none (nothing reads them)"));
  for (;;) {
    try {
      hooks.resume_from = from ? &*from : nullptr;
      RoundLoopResult result = run_round_loop(*cur, channel, o.round_timeout_s, hooks);
      log(phase_memory_line("the rounding"));
      channel.publish_final_progress();
      deliver_final_estimate(s, *cur, std::move(result), o, log, t0);
      break;
    } catch (const RepartitionRequested& order) {
      refuse_if_lost(order.assignment, o.id, o.net.session.run_id);
      if (!replication.enabled() || cur != &local)
        throw RunFailure(kExitRunFailed, std::string(order.what()) +
                                             ": this run does not replicate for a second loss");
      cur = &replication.take_over(local, order.assignment, o.net.timeout_s);
      from.reset();
    } catch (const RollbackRequested& order) {
      std::cerr << log.tag << ": " << order.what() << ": resuming from the snapshot of round "
                << order.round << "\n";
      from = prepare_rollback(s, keeper, order, o.net.timeout_s);
    }
  }
  if (!o.checkpoint_dir.empty()) {
    const auto& cs = keeper.stats();
    char buf[200];
    std::snprintf(buf, sizeof(buf),
                  "%s: checkpoints: %llu written, %.1f ms in total (%.2f ms each), %llu bytes "
                  "each\n",
                  log.tag.c_str(), static_cast<unsigned long long>(cs.writes), cs.write_s * 1e3,
                  cs.writes ? cs.write_s * 1e3 / static_cast<double>(cs.writes) : 0.0,
                  static_cast<unsigned long long>(cs.last_bytes));
    std::cerr << buf;
    std::remove(keeper.path().c_str());  // the run is complete: nothing to rejoin
  }
}

}  // namespace

std::optional<AgentCheckpoint> find_restart_checkpoint(const AgentOptions& o) {
  if (o.checkpoint_dir.empty()) return std::nullopt;
  const std::string path = checkpoint_path(o.checkpoint_dir, o.id);
  if (access(path.c_str(), F_OK) != 0) return std::nullopt;
  AgentCheckpoint restart = load_checkpoint(path, o.net.session.run_id, o.id, o.robots);
  std::cerr << agent_tag(o.id) << ": rejoining run '" << o.net.session.run_id
            << "' from checkpoint " << path << " (rounds " << restart.snapshots.front().round
            << ".." << restart.snapshots.back().round << ")\n";
  std::this_thread::sleep_for(Seconds(1.5 * o.net.session.lease_s));
  return restart;
}

void run_agent(const AgentOptions& o, AgentSession& s, std::optional<AgentCheckpoint> restart) {
  // TESSERA_DDS_TRACE=1 (transport/dds_trace.hpp) also stamps and prints the phase lines.
  const char* trace = std::getenv("TESSERA_DDS_TRACE");
  const bool traced = trace && *trace && *trace != '0';
  const AgentLog log{agent_tag(o.id), o.verbose || traced, traced};
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (restart) {
      solve(s, o, log, restart->local, restart, nullptr, t0);
    } else {
      const RunSetup setup = set_up_fresh_run(s, o, log);
      solve(s, o, log, setup.local, restart, &setup, t0);
    }
  } catch (const RepartitionRequested& r) {  // outside the round loop (during set-up)
    refuse_if_lost(r.assignment, o.id, o.net.session.run_id);
    throw;
  } catch (const RunStopped&) {
    // The stop's own cause (a lost peer, an ABORT, a signal), not the unwinding's.
    const StopInfo stop = s.mailroom().stop_info().value_or(
        StopInfo{kExitRunFailed, "stopped", false, std::nullopt, ""});
    throw RunFailure(stop.exit_code, stop.reason, !stop.remote);
  }
}

}  // namespace tessera::agent
