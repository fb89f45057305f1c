#include "agent/run_setup.hpp"

#include <unistd.h>

#include <algorithm>
#include <iostream>
#include <optional>
#include <string>
#include <tessera/util/input_error.hpp>
#include <utility>
#include <vector>

#include "agent/agent_gate.hpp"
#include "agent/dds_channel.hpp"
#include "agent/handoff_exchange.hpp"
#include "agent/lost_for_good.hpp"
#include "agent/robot_data.hpp"
#include "agent/share_announcement.hpp"
#include "launch/heap_retention.hpp"
#include "launch/process_tuning.hpp"
#include "runtime/early_chordal.hpp"
#include "runtime/initialization_stage.hpp"
#include "runtime/known_inlier_start.hpp"
#include "runtime/local_dump.hpp"
#include "runtime/phase_memory.hpp"
#include "runtime/preloaded_graph.hpp"
#include "runtime/team_memory.hpp"
#include "transport/assignment_options.hpp"
#include "transport/run_failure.hpp"
#include "transport/run_identity.hpp"

namespace tessera::agent {

using namespace tessera::transport;

namespace {

// The whole graph's endpoints from the assignment, checked: the agents build their block
// layout from them, so a pose out of range must stop the run here.
std::vector<std::pair<std::uint32_t, std::uint32_t>> structure_of(
    const wire::PartitionAssignment& asg, std::size_t num_poses) {
  if (asg.edge_i().size() != asg.edge_j().size())
    throw RunFailure(kExitRunFailed, "the assignment's structure arrays differ in length");
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;
  structure.reserve(asg.edge_i().size());
  for (std::size_t e = 0; e < asg.edge_i().size(); ++e) {
    if (asg.edge_i()[e] >= num_poses || asg.edge_j()[e] >= num_poses)
      throw RunFailure(kExitRunFailed, "the assignment's structure names a pose out of range");
    structure.emplace_back(asg.edge_i()[e], asg.edge_j()[e]);
  }
  return structure;
}

// The run's options as the assignment carries them (transport/assignment_options.hpp), with
// this host's factor budget: one host's factors share one budget (runtime/team_memory.hpp).
RunOptions host_run_options(const wire::PartitionAssignment& asg) {
  RunOptions ro = transport::run_options_of(asg);
  ro.max_factor_entries = team_factor_cap(asg.num_agents());
  return ro;
}

}  // namespace

RunSetup set_up_fresh_run(AgentSession& s, const AgentOptions& o, const AgentLog& log) {
  Mailroom& room = s.mailroom();
  RunSetup out;

  // 1. Our share of the graph: robot I's part of the whole file, or the robot's own file.
  RobotShare share = load_robot_share(o.graph, o.id, o.robots);
  launch::release_freed_heap();  // the file's text
  log("read " + o.graph + ": poses [" + std::to_string(share.begin) + ", " +
      std::to_string(share.end) + ") of " + std::to_string(share.num_poses) + ", " +
      std::to_string(share.measurements.size()) + " measurements");
  log(phase_memory_line("reading its share"));
  // Agent 0 solves the chordal start while discovery and the partition run; the stage uses it
  // only if the gathered values are this graph's (runtime/early_chordal.hpp). Only for a graph
  // the fork server parsed: the agent holds no whole graph otherwise.
  std::optional<EarlyChordal> early;
  if (o.early_chordal && o.id == 0)
    if (const PoseGraph* whole = preloaded_graph(o.graph)) {
      early.emplace(*whole);
      log("chordal initialization of the whole graph started");
    }

  // 2. Before announcing: know the coordinator and, in a secured run, have authenticated every
  // other process. On the way the participant may be re-created (UDP only when the
  // coordinator's run survives killed agents; a stalled DDS Security handshake): nothing is
  // announced yet, so that is invisible to the run (transport/peer_gate.hpp).
  pass_agent_gate(s, o);
  log(std::string("peers known") + s.options().transports_note());

  // 3. Announce the structure (endpoints only).
  s.publish(announcement_of(share, o.net.session.run_id, o.id, o.robots));
  log("announced");

  // 4. The assignment.
  wire::PartitionAssignment asg;
  WaitStatus got = s.assignments().take(Seconds(o.net.timeout_s), &asg);
  expect_ready(got, room, o.net.timeout_s, "the partition assignment from the coordinator",
               s.peers_ever_seen() == 0
                   ? "no process of run '" + o.net.session.run_id + "' seen on domain " +
                         std::to_string(s.domain()) + " (is the coordinator running?)"
                   : "");
  // A process started again after the run gave its block to the survivors.
  refuse_if_lost(asg, o.id, o.net.session.run_id);
  refuse_if_lost(s, o.id);
  check_assignment(share, asg, o.robots, o.graph);
  // The coordinator's partition is done: the rounds need wake-ups to run at once again
  // (launch/process_tuning.hpp).
  const std::string unbatched = launch::end_agent_startup();
  if (!unbatched.empty()) log(unbatched);
  out.rejoin_enabled = asg.rejoin_timeout_s() > 0;
  out.replicas = asg.replicas();
  out.replica_every = std::max<std::uint32_t>(1, asg.replica_every());
  out.status_relay = asg.status_relay();
  log("assignment received (" +
      std::to_string(std::count(asg.owner().begin(), asg.owner().end(), o.id)) + " poses owned)");
  log(phase_memory_line("the assignment"));

  // 5. Everyone's endpoints matched before any volatile agent-to-agent message.
  // With replicas a process restarted after the run gave its block away may have taken the
  // first epoch's assignment before the one naming it lost arrived; the survivors will never
  // be READY for it, so it looks again between short waits.
  std::string missing;
  const auto ready_until = std::chrono::steady_clock::now() + Seconds(o.net.timeout_s);
  WaitStatus ready = WaitStatus::kTimeout;
  for (;;) {
    const Seconds left = ready_until - std::chrono::steady_clock::now();
    ready = s.ready_barrier(out.replicas > 0 ? std::min(left, Seconds(0.5)) : left, &missing);
    if (ready != WaitStatus::kTimeout || std::chrono::steady_clock::now() >= ready_until) break;
    refuse_if_lost(s, o.id);
  }
  expect_ready(ready, room, o.net.timeout_s, "the other processes to be ready", missing);
  log("all processes ready");

  // 6. Initial poses of our share (core/runtime/initialization_stage.hpp), before they move.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure =
      structure_of(asg, share.num_poses);
  // Copied out: the assignment's own endpoint arrays would otherwise stay through the
  // initialisation and the hand-off (8 bytes a measurement of the whole graph: 16 MB an agent
  // at 1M poses).
  std::vector<std::uint32_t>().swap(asg.edge_i());
  std::vector<std::uint32_t>().swap(asg.edge_j());
  DdsProtocolChannel channel(s);
  const RunOptions run_options = host_run_options(asg);
  SetupTurnOptions turns;
  turns.max_at_once = asg.setup_at_once();
  turns.after_local_solve = [] { launch::release_freed_heap(); };
  try {
    turns.validate();
  } catch (const InputError& e) {
    throw RunFailure(kExitRunFailed, std::string("the assignment: ") + e.what());
  }
  // The input's own known-inlier flags (a dpgo CSV file's), every measurement's.
  std::vector<bool> known_flags;
  if (!asg.known_inlier().empty()) {
    known_flags.assign(structure.size(), false);
    for (std::uint32_t e : asg.known_inlier()) {
      if (e >= structure.size())
        throw RunFailure(kExitRunFailed, "the assignment flags a measurement out of range");
      known_flags[e] = true;
    }
  }
  double init_s = 0.0;
  bool init_early = false;
  {
    // A robust run also computes the known inliers' start when they connect the poses; the
    // agents vote between the two before the first solve, like the in-process engine
    // (robust/gnc_distributed.hpp, known_inlier_poses(); robust/gnc_agent.hpp).
    std::optional<KnownInlierStart> known;
    if (run_options.robust.kind != RobustKind::kNone && run_options.gnc_known_start)
      known = known_inlier_start(share, structure, run_options.robust.known_inliers, known_flags);
    if (known) {
      auto [init, known_init] = run_initialization_stages(
          share, known->share, o.id, o.robots, structure, known->structure, asg.initialization(),
          "distributed", o.graph, channel, o.round_timeout_s, early ? &*early : nullptr, turns);
      share.initial = std::move(init.poses);
      share.known_initial = std::move(known_init.poses);
      init_s = init.seconds + known_init.seconds;
      init_early = init.early;
      log("initialisation '" + init.method + "' and 'distributed' of the known inliers done in " +
          std::to_string(static_cast<long>((init.seconds + known_init.seconds) * 1000)) + " ms");
    } else {
      InitializationResult init =
          run_initialization_stage(share, o.id, o.robots, structure, asg.initialization(), o.graph,
                                   channel, o.round_timeout_s, early ? &*early : nullptr, turns);
      share.initial = std::move(init.poses);
      init_s = init.seconds;
      init_early = init.early;
      log("initialisation '" + init.method + "' done in " +
          std::to_string(static_cast<long>(init.seconds * 1000)) + " ms" +
          (init.early ? " (solved while the run started)" : ""));
    }
  }

  early.reset();                 // an unused early solve: wait for it, drop it
  launch::release_freed_heap();  // the initialisation's factorizations and the assignment's copy
  log(phase_memory_line("the initialisation"));

  // 7. Hand-off, peer to peer: exactly one message to every other agent. A peer sends its
  // hand-off when its initialisation is done, which is computation (minutes for 25 agents of a
  // 1M-pose grid on 2 cores: 30 s timed out), so the wait is bounded like a round's, not like a
  // network step; a dead peer is noticed by its lease meanwhile.
  const auto handoff_start = std::chrono::steady_clock::now();
  HandoffSending sending;
  std::vector<ReceivedHandoff> received =
      exchange_handoffs(s, share, asg.owner(), o.id, o.robots, o.net.session.run_id,
                        std::max(o.net.timeout_s, o.round_timeout_s), &sending);
  out.local = assemble_local(share, asg.owner(), o.id, o.robots, std::move(received), run_options);
  out.local.structure = std::move(structure);
  out.local.known_inlier = std::move(known_flags);
  log("hand-off complete: " + std::to_string(out.local.owned.size()) + " poses, " +
      std::to_string(out.local.measurements.size()) + " measurements; sent " +
      std::to_string(sending.parts) + " parts in " +
      std::to_string(static_cast<long>(sending.send_s * 1000)) +
      " ms (waiting for acknowledgements " +
      std::to_string(static_cast<long>(sending.ack_wait_s * 1000)) + " ms)");
  if (o.id == 0)  // the coordinator's summary splits the time to the first round with these
    channel.report(SetupTimesReport{
        init_s,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - handoff_start).count(),
        init_early});
  if (!o.dump_local.empty()) write_local_dump(out.local, o.dump_local);
  launch::release_freed_heap();  // the hand-off's messages
  log(phase_memory_line("the hand-off"));
  return out;
}

}  // namespace tessera::agent
