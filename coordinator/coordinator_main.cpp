// tessera-coordinator: the lightweight process of a distributed run. It waits for the N
// agents, partitions the graph structure they announce (never measurement values),
// publishes the assignment and gathers the final estimate. See docs/dds-runtime.md.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "arguments.hpp"
#include "coordinator/partition_step.hpp"
#include "coordinator/rejoin_arbiter.hpp"
#include "coordinator/run_monitor.hpp"
#include "coordinator/run_structure.hpp"
#include "coordinator/survivor_step.hpp"
#include "distributed/distributed_solver.hpp"
#include "graph/pose_graph.hpp"
#include "io/g2o_writer.hpp"
#include "io/tum_writer.hpp"
#include "json_writer.hpp"
#include "session_args.hpp"
#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"
#include "transport/session.hpp"
#include "transport/signal_watcher.hpp"
#include "util/input_error.hpp"

using namespace tessera;
using namespace tessera::transport;

// Status phase of agent 0's final report (agent/round_loop.hpp: kFinalReportPhase).
constexpr std::uint32_t agent_final_report_phase = 200;
// Agent 0's certificate reports (kCertificateReportPhase, kCertificateBytesPhase).
constexpr std::uint32_t agent_certificate_report_phase = 201;
constexpr std::uint32_t agent_certificate_bytes_phase = 202;

namespace {

// %s: the shared DDS session options (cli/session_args.hpp).
constexpr const char* kHelp = R"(usage: tessera-coordinator --agents N [options]

The coordinator of a distributed Tessera run. Waits for N tessera-agent processes of the
same run id, receives their graph structure (edge endpoints only), partitions it, publishes
the assignment and the algorithm options, then gathers every agent's final poses and writes
the merged result. It never receives measurement values.

options:
  --agents N           number of agents of the run (required)
  --run-timeout S      bound on the wait for the final estimates, seconds (default 3600)
  --partition PRESET   sequential, fast, eco, strong or highest (default eco)
  --partition-seed K   seed of the partitioner (default 1)
  --rank R             rank r of the relaxation sent to the agents (default 0 = core's, 5)
  --algorithm NAME     solver name sent to the agents (default: core's default)
  --init NAME          initialisation the agents run: chordal | distributed | file (the
                       VERTEX poses) (default: the in-process engine's, chordal)
  --max-rounds K       round limit sent to the agents (default 0 = core's default)
  --grad-tol X         gradient-norm tolerance sent to the agents (default 0 = core's default)
  --rel-cost-tol X     relative cost tolerance sent to the agents (default 0 = core's default)
  --seed K             solver seed sent to the agents (default 1)
  --certify            agents certify the optimum distributedly and climb the staircase
                       after the solve (docs/distributed-certification.md; default off)
  --output FILE        write the merged poses as g2o (VERTEX lines only)
  --tum FILE           write the merged poses in the TUM format
  --summary FILE       write a JSON summary of the run
  --graph-name NAME    label of the graph in the summary (default "")
  --progress           print round progress (sum of the agents' cost and gradient norm)
  --rejoin-timeout S   when an agent process dies, wait up to S seconds for it to be
                       restarted (same id, --checkpoint-dir) and rejoin; every agent then rolls
                       back to a common checkpoint round. 0 = stop the run at once (default 0)
  --replicas K         replicate every agent's measurements and lifted poses to K other
                       agents; an agent lost for good (not back within --rejoin-timeout) then
                       has its block re-partitioned among the survivors, and the run goes on
                       with N-1 agents. 0 = off: the run stops (default 0)
  --replica-every K    rounds between lifted-pose replicas (default 10)
  --status-interval S  print a status line (agents alive, their rounds, lagging or lost
                       agents) every S seconds and on changes; 0 = off (default 5)
  --verbose            print each phase
  --help               this text

DDS session options (shared with tessera-agent and tessera launch):
%s
exit codes: 0 done, 1 the run failed (lost agent, abort, timeout), 2 bad options or input,
128+signal when interrupted (SIGINT 130, SIGTERM 143).
)";

struct CoordinatorArgs {
  std::uint32_t agents = 0;
  cli::SessionArgs net;  ///< run id, domain, lease, peers, --timeout (cli/session_args.hpp)
  double run_timeout_s = 3600;
  std::string partition = "eco";
  std::uint64_t partition_seed = 1;
  std::uint32_t rank = 0;
  std::string algorithm, init;
  std::uint32_t max_rounds = 0;
  double grad_tol = 0, rel_cost_tol = 0;
  std::uint64_t seed = 1;
  std::string output, tum, summary, graph_name;
  bool progress = false, verbose = false;
  double rejoin_timeout_s = 0;
  double status_interval_s = 5;
  std::uint32_t replicas = 0, replica_every = 10;
  bool certify = false;
};

CoordinatorArgs parse(const std::vector<std::string>& argv) {
  cli::Arguments args(
      argv,
      cli::with_session_options(
          {"agents", "run-timeout", "partition", "partition-seed", "rank", "algorithm", "init",
           "max-rounds", "grad-tol", "rel-cost-tol", "seed", "output", "tum", "summary",
           "graph-name", "rejoin-timeout", "status-interval", "replicas", "replica-every"},
          cli::SessionArgsFor::kProcess),
      {"progress", "verbose", "help", "certify"});
  if (!args.positional().empty())
    throw InputError("unexpected argument '" + args.positional().front() + "' (see --help)");
  CoordinatorArgs a;
  if (!args.has("agents")) throw InputError("option --agents is required (see --help)");
  long agents = args.get_long("agents", 0);
  if (agents < 1 || agents > 1000) throw InputError("option --agents: must be 1..1000");
  a.agents = static_cast<std::uint32_t>(agents);
  a.net = cli::parse_session_args(args, cli::SessionArgsFor::kProcess);
  a.run_timeout_s = args.get_double("run-timeout", a.run_timeout_s);
  if (!(a.run_timeout_s > 0)) throw InputError("option --run-timeout: must be positive");
  a.partition = args.get_or("partition", a.partition);
  auto nonneg = [&](const char* name, long fallback) {
    long v = args.get_long(name, fallback);
    if (v < 0) throw InputError(std::string("option --") + name + ": must not be negative");
    return v;
  };
  a.partition_seed = static_cast<std::uint64_t>(nonneg("partition-seed", 1));
  a.rank = static_cast<std::uint32_t>(nonneg("rank", 0));
  a.algorithm = args.get_or("algorithm", "");
  a.init = args.get_or("init", init_name(DistributedOptions{}.initialization));
  parse_init(a.init);  // throws InputError naming the valid ones
  a.max_rounds = static_cast<std::uint32_t>(nonneg("max-rounds", 0));
  a.grad_tol = args.get_double("grad-tol", 0);
  a.rel_cost_tol = args.get_double("rel-cost-tol", 0);
  if (a.grad_tol < 0) throw InputError("option --grad-tol: must not be negative");
  if (a.rel_cost_tol < 0) throw InputError("option --rel-cost-tol: must not be negative");
  a.seed = static_cast<std::uint64_t>(nonneg("seed", 1));
  a.output = args.get_or("output", "");
  a.tum = args.get_or("tum", "");
  a.summary = args.get_or("summary", "");
  a.graph_name = args.get_or("graph-name", "");
  a.progress = args.has("progress");
  a.rejoin_timeout_s = args.get_double("rejoin-timeout", a.rejoin_timeout_s);
  if (!(a.rejoin_timeout_s >= 0 && a.rejoin_timeout_s <= 86400))
    throw InputError("option --rejoin-timeout: must be 0..86400 seconds");
  a.status_interval_s = args.get_double("status-interval", a.status_interval_s);
  if (!(a.status_interval_s >= 0 && a.status_interval_s <= 86400))
    throw InputError("option --status-interval: must be 0..86400 seconds");
  a.replicas = static_cast<std::uint32_t>(nonneg("replicas", 0));
  if (a.replicas > 8) throw InputError("option --replicas: must be 0..8");
  a.replica_every = static_cast<std::uint32_t>(nonneg("replica-every", 10));
  if (a.replica_every < 1) throw InputError("option --replica-every: must be >= 1");
  a.verbose = args.has("verbose");
  a.certify = args.has("certify");
  return a;
}

class Coordinator {
 public:
  Coordinator(const CoordinatorArgs& a, SignalWatcher& signals) : a_(a), signals_(signals) {}

  int run() {
    SessionOptions so = a_.net.session;
    so.coordinator = true;
    so.num_agents = a_.agents;
    so.verbose = a_.verbose;
    // A run that survives killed agents talks UDP only (see transport/qos.hpp).
    so.shared_memory = a_.rejoin_timeout_s <= 0;
    try {
      session_ = std::make_unique<Session>(so);
    } catch (const InputError& e) {
      std::cerr << "tessera-coordinator: error: " << e.what() << "\n";
      return kExitBadInput;
    } catch (const std::exception& e) {
      std::cerr << "tessera-coordinator: error: " << e.what() << "\n";
      return kExitRunFailed;
    }
    Session& s = *session_;
    signals_.start([&s](int signo) {
      s.mailroom().request_stop(exit_code_for_signal(signo),
                                "interrupted by " + signal_name(signo));
    });
    int code = kExitOk;
    try {
      phases();
    } catch (const RunFailure& f) {
      code = leave(f.exit_code(), f.what(), f.tell_others());
    } catch (const InputError& e) {
      code = leave(kExitBadInput, e.what(), true);
    } catch (const std::exception& e) {
      if (auto stop = s.mailroom().stop_info())
        code = leave(stop->exit_code, stop->reason, !stop->remote);
      else
        code = leave(kExitRunFailed, e.what(), true);
    }
    signals_.stop();
    s.close();
    return code;
  }

 private:
  void log(const std::string& what) {
    if (a_.verbose) std::cerr << "tessera-coordinator: " << what << "\n";
  }

  // Prints the error and tells the agents (ABORT; an agent's abort is relayed as is, so
  // every agent learns the cause even if it never heard from that agent), then lingers
  // briefly so the ABORT arrives before the coordinator disappears.
  int leave(int code, const std::string& why, bool own) {
    std::cerr << "tessera-coordinator: error: " << why << "\n";
    try {
      session_->send_control(wire::CONTROL_ABORT, own ? "coordinator: " + why : why);
      session_->linger_for_control(Seconds(std::min(3.0, a_.net.timeout_s)));
    } catch (const std::exception&) {
      // Leaving anyway: the agents notice the coordinator disappear.
    }
    return code;
  }

  static double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  }

  void phases() {
    Session& s = *session_;
    Mailroom& room = s.mailroom();
    const auto t0 = std::chrono::steady_clock::now();
    const std::uint32_t N = a_.agents;

    // 1. Every agent's announcement (TRANSIENT_LOCAL: agents may have started first).
    std::string missing;
    auto all_announced = [&](const std::deque<wire::AgentAnnouncement>& q) {
      std::set<std::uint32_t> have;
      for (const auto& m : q) {
        if (m.agent_id() >= N || m.num_agents() != N)
          return true;  // let merge_announcements explain
        have.insert(m.agent_id());
      }
      missing.clear();
      std::string present;
      for (std::uint32_t k = 0; k < N; ++k) {
        std::string& list = have.count(k) ? present : missing;
        list += (list.empty() ? "" : ", ") + std::to_string(k);
      }
      if (!missing.empty())
        missing =
            "missing agent " + missing + (present.empty() ? "" : " (have agent " + present + ")");
      return have.size() == N;
    };
    expect_ready(s.announcements().wait_for(all_announced, Seconds(a_.net.timeout_s)), room,
                 a_.net.timeout_s,
                 std::to_string(N) + " agents of run '" + a_.net.session.run_id + "' on domain " +
                     std::to_string(s.domain()),
                 missing);
    std::vector<wire::AgentAnnouncement> announcements = s.announcements().take_all();
    discovery_ms_ = ms_since(t0);
    coordinator::RunStructure rs =
        coordinator::merge_announcements(announcements, N, a_.net.session.run_id);
    announcements.clear();
    log("all " + std::to_string(N) + " agents announced (" +
        std::to_string(static_cast<long>(discovery_ms_)) + " ms): " + std::to_string(rs.num_poses) +
        " poses, " + std::to_string(rs.num_measurements) + " measurements");

    // 2. Partition and publish the assignment.
    coordinator::PartitionStepResult part =
        coordinator::partition_for_agents(rs.graph, N, a_.partition, a_.partition_seed);
    log("partition (" + a_.partition + "): cut " + std::to_string(part.cut_edges) +
        " measurements in " + std::to_string(part.ms) + " ms");
    wire::PartitionAssignment asg;
    asg.run_id(a_.net.session.run_id);
    asg.num_agents(N);
    asg.num_poses(static_cast<std::uint32_t>(rs.num_poses));
    asg.dim(static_cast<std::uint32_t>(rs.d));
    asg.rank(a_.rank);
    asg.owner(part.owner);
    asg.edge_i(rs.edge_i);
    asg.edge_j(rs.edge_j);
    asg.algorithm(a_.algorithm);
    asg.initialization(a_.init);
    asg.max_rounds(a_.max_rounds);
    asg.grad_norm_tolerance(a_.grad_tol);
    asg.relative_cost_tolerance(a_.rel_cost_tol);
    asg.seed(a_.seed);
    asg.partition_ms(part.ms);
    asg.rejoin_timeout_s(a_.rejoin_timeout_s);
    asg.replicas(a_.replicas);
    asg.replica_every(a_.replica_every);
    loss_.owner = part.owner;
    for (std::uint32_t k = 0; k < N; ++k) loss_.expected.push_back(k);
    base_assignment_ = asg;
    asg.certify(a_.certify);
    s.publish(asg);
    expect_ready(s.ready_barrier(Seconds(a_.net.timeout_s), &missing), room, a_.net.timeout_s,
                 "the agents to be ready", missing);
    log("all agents ready");

    // 3. Final estimates (progress from round statuses meanwhile; lost agents go to the
    // arbiter, which waits for them to rejoin).
    const auto t_run = std::chrono::steady_clock::now();
    loss_.t_run = t_run;
    using Clock = std::chrono::steady_clock;
    coordinator::RejoinArbiter arbiter(N, a_.rejoin_timeout_s);
    const bool arbitrate = a_.rejoin_timeout_s > 0 || a_.replicas > 0;
    if (arbitrate) s.set_agent_loss_tolerated(true);
    std::optional<coordinator::RunMonitor> monitor;
    if (a_.status_interval_s > 0)
      monitor.emplace(N, coordinator::MonitorOptions{a_.status_interval_s, 2, 3.0}, std::cout,
                      t_run);
    std::map<std::pair<std::uint32_t, std::uint32_t>,
             std::pair<std::uint32_t, std::pair<double, double>>>
        progress;
    auto finals_missing = [&]() {
      std::set<std::uint32_t> have;
      for (const auto& f : s.finals().queued_locked())
        if (f.epoch() >= loss_.epoch) have.insert(f.sender());
      std::string out;
      for (std::uint32_t k : loss_.expected)
        if (!have.count(k)) out += (out.empty() ? "agent " : ", agent ") + std::to_string(k);
      return out;
    };
    const bool watch = monitor || arbitrate;
    for (;;) {
      const double left = a_.run_timeout_s - ms_since(t_run) / 1000.0;
      std::string absent;
      // Lost peers are noticed by polling the session (a few times a second) when watching.
      const double nap = watch ? std::min(std::max(0.0, left), 0.25) : std::max(0.0, left);
      WaitStatus st = room.wait_for(
          [&] {
            absent = finals_missing();
            return (absent.empty() && have_final_report_) ||
                   !s.status_watch().queued_locked().empty() ||
                   !s.rejoins().queued_locked().empty();
          },
          Seconds(nap));
      if (st == WaitStatus::kStopped || (st == WaitStatus::kTimeout && left <= 0))
        expect_ready(st, room, a_.run_timeout_s, "the final estimates", "none yet from " + absent);
      const auto now = Clock::now();
      for (const auto& m : s.status_watch().take_all()) {
        if (m.epoch() < std::max(arbiter.epoch(), loss_.epoch)) continue;  // before a rollback
        if ((m.phase() == 1 || m.phase() == 5) && m.sender() < loss_.expected.size()) {
          // After a re-partition senders are protocol ids: positions among the survivors.
          const std::uint32_t agent = loss_.expected[m.sender()];
          if (loss_.epoch == 0) arbiter.on_status(agent, m.round());
          if (monitor) monitor->on_status(agent, m.round(), now);
        }
        if (m.phase() == agent_certificate_report_phase) {
          certificate_ = {m.restart_vote(), m.cost(), m.grad_norm_sq(), m.block_grad_norm()};
          continue;
        }
        if (m.phase() == agent_certificate_bytes_phase) {
          certificate_bytes_ = {m.cost(), m.grad_norm_sq(), m.block_grad_norm()};
          continue;
        }
        if (m.phase() == agent_final_report_phase) {  // agent 0's summary of the solve
          final_cost_ = m.cost();
          final_grad_norm_ = std::sqrt(m.grad_norm_sq());
          final_restarts_ = static_cast<std::uint32_t>(m.block_grad_norm());
          have_final_report_ = true;
          continue;
        }
        // Only the round statuses (core's phases 1 and 5) make progress lines.
        if (m.phase() != 1 && m.phase() != 5) continue;
        auto& p = progress[{m.round(), m.phase()}];
        p.first += 1;
        p.second.first += m.cost();
        p.second.second += m.grad_norm_sq();
        const std::uint32_t active = static_cast<std::uint32_t>(loss_.expected.size());
        if ((m.phase() == 1 || m.phase() == 5) && loss_.epoch == 0) loss_.last_round = m.round();
        if (p.first == active && a_.progress) {
          char buf[160];
          std::snprintf(buf, sizeof(buf), "round %u%s: cost %.10g, grad norm %.3e\n", m.round(),
                        m.phase() == 5 ? " (restart)" : "", p.second.first,
                        std::sqrt(p.second.second));
          std::cout << buf << std::flush;
        }
        if (p.first == active) {
          progress.erase({m.round(), m.phase()});
          // Round timing from the status completions the coordinator sees: excludes the
          // fixed costs (hand-off, initialisation, rounding, shutdown) that solve_ms holds.
          const double t = ms_since(t_run);
          if (completed_statuses_ == 0) first_status_ms_ = t;
          last_status_ms_ = t;
          if (m.phase() == 1) ++completed_statuses_;
        }
      }
      if (watch) {
        const std::vector<std::uint32_t> lost = s.lost_agents();
        if (arbitrate && loss_.epoch == 0)
          for (auto k : lost) arbiter.on_lost(k, now);
        if (loss_.epoch > 0) {
          // A survivor lost too (for longer than the rejoin window: a loaded host can drop
          // and rediscover a live peer) is a second loss, which the replicas do not cover.
          std::map<std::uint32_t, Clock::time_point> still;
          for (auto k : lost)
            if (std::find(loss_.lost.begin(), loss_.lost.end(), k) == loss_.lost.end())
              still[k] = loss_.second.count(k) ? loss_.second[k] : now;
          loss_.second = still;
          for (const auto& [k, since] : still)
            if (std::chrono::duration<double>(now - since).count() > a_.rejoin_timeout_s)
              throw RunFailure(kExitRunFailed, "lost agent " + std::to_string(k) +
                                                   " after a re-partition: a second loss is "
                                                   "not covered by the replicas");
        }
        if (monitor) monitor->set_lost(lost, now);
        for (const auto& c : s.rejoins().take_all()) {
          arbiter.on_rejoin({c.agent(), c.round(), c.round_prev(), c.nonce()}, now);
          if (monitor)
            monitor->event("agent " + std::to_string(c.agent()) +
                               " restarted, asks to rejoin (checkpoint rounds " +
                               std::to_string(c.round_prev()) + ", " + std::to_string(c.round()) +
                               ")",
                           now);
        }
        if (arbitrate && loss_.epoch == 0) decide_on_losses(arbiter, monitor, progress, now, rs);
        if (monitor) monitor->tick(now);
      }
      if (have_final_report_ && s.finals().size() >= loss_.expected.size() &&
          room.wait_for([&] { return finals_missing().empty(); }, Seconds(0)) == WaitStatus::kReady)
        break;
    }
    solve_ms_ = ms_since(t_run);

    // 4. Merge.
    std::vector<Pose> poses(rs.num_poses);
    std::vector<bool> seen(rs.num_poses, false);
    std::vector<std::uint64_t> bytes(N, 0);
    std::uint32_t rounds = 0;
    for (const auto& f : s.finals().take_all()) {
      if (f.sender() >= N || f.epoch() < loss_.epoch) continue;
      bytes[f.sender()] = f.bytes_sent();
      rounds = std::max(rounds, f.rounds());
      auto list = final_poses(f);
      for (auto& [id, pose] : list) {
        if (id >= rs.num_poses || loss_.owner[id] != f.sender())
          throw RunFailure(kExitRunFailed, "agent " + std::to_string(f.sender()) +
                                               " returned pose " + std::to_string(id) +
                                               " which it does not own");
        if (pose.dim() != rs.d)
          throw RunFailure(kExitRunFailed, "final pose of the wrong dimension");
        poses[id] = std::move(pose);
        seen[id] = true;
      }
    }
    for (std::size_t id = 0; id < rs.num_poses; ++id)
      if (!seen[id])
        throw RunFailure(kExitRunFailed, "pose " + std::to_string(id) + " is missing from agent " +
                                             std::to_string(loss_.owner[id]) + "'s final estimate");
    if (!a_.output.empty()) {
      PoseGraph g;
      g.d = rs.d;
      g.num_poses = rs.num_poses;
      g.source = "tessera-coordinator run " + a_.net.session.run_id;
      write_g2o(g, poses, a_.output);
    }
    if (!a_.tum.empty()) write_tum(poses, a_.tum);
    if (!a_.summary.empty()) write_summary(rs, part, bytes, rounds, ms_since(t0));

    // 5. Tell the agents they may leave.
    s.send_control(wire::CONTROL_FINISHED);
    s.flush(Seconds(std::min(3.0, a_.net.timeout_s)));
    s.set_peer_loss_fatal(false);
    std::uint64_t total_bytes = 0;
    for (auto b : bytes) total_bytes += b;
    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "tessera-coordinator: done: %u agents, %zu poses, %u round(s), discovery %.0f "
                  "ms, partition %.1f ms, "
                  "%llu bytes sent by agents, %.2f s\n",
                  static_cast<std::uint32_t>(loss_.expected.size()), rs.num_poses, rounds,
                  discovery_ms_, part.ms, static_cast<unsigned long long>(total_bytes),
                  ms_since(t0) / 1000.0);
    std::cerr << buf;
  }

  // Acts on the arbiter's decision (coordinator/rejoin_arbiter.hpp): a rollback order to
  // every agent, or a clean stop naming the lost agent.
  template <class Progress>
  void decide_on_losses(coordinator::RejoinArbiter& arbiter,
                        std::optional<coordinator::RunMonitor>& monitor, Progress& progress,
                        std::chrono::steady_clock::time_point now,
                        const coordinator::RunStructure& rs) {
    const coordinator::LossDecision d = arbiter.decide(now);
    using Kind = coordinator::LossDecision::Kind;
    // Lost for good: re-partition. Only the agent whose rejoin window closed leaves: a peer
    // dropped at the same moment may be a false alarm of a loaded host (it reappears).
    if (d.kind == Kind::kGiveUp && a_.replicas > 0) {
      const std::vector<std::uint32_t> lost = session_->lost_agents();
      if (std::find(lost.begin(), lost.end(), d.agent) == lost.end()) {
        // Alive again: a false alarm of the lease on a busy host, not a loss.
        arbiter.forget(d.agent);
        std::cerr << "tessera-coordinator: agent " << d.agent
                  << " is back (false alarm): no re-partition\n";
        return;
      }
      const coordinator::SurvivorAssignment sa = coordinator::reassign_for_survivors(
          rs.graph, loss_.owner, a_.agents, {d.agent}, arbiter.epoch() + 1);
      wire::PartitionAssignment asg = base_assignment_;
      asg.epoch(sa.epoch);
      asg.owner(sa.owner);
      asg.survivors(sa.survivors);
      asg.lost(sa.lost);
      session_->publish(asg);
      loss_.epoch = sa.epoch;
      loss_.owner = sa.owner;
      loss_.expected = sa.survivors;
      loss_.lost = sa.lost;
      loss_.moved_poses = sa.moved_poses;
      loss_.cut_edges = sa.cut_edges;
      loss_.at_ms = ms_since(loss_.t_run);
      have_final_report_ = false;  // the survivors' run reports again
      progress.clear();
      const std::string what = "agent(s) lost for good; re-partitioned " +
                               std::to_string(sa.moved_poses) + " poses among " +
                               std::to_string(sa.survivors.size()) + " survivors (epoch " +
                               std::to_string(sa.epoch) + ", " + d.reason + ")";
      if (monitor)
        monitor->event(what, now);
      else
        std::cerr << "tessera-coordinator: " << what << "\n";
      return;
    }
    if (d.kind == Kind::kGiveUp)
      throw RunFailure(kExitRunFailed, "lost agent " + std::to_string(d.agent) + " of run '" +
                                           a_.net.session.run_id + "': " + d.reason);
    if (d.kind != Kind::kRollback) return;
    for (const auto& r : d.rejoined) {
      wire::Control c;
      c.kind(wire::CONTROL_ROLLBACK);
      c.round(d.round);
      c.epoch(d.epoch);
      c.agent(r.agent);
      c.nonce(r.nonce);
      c.reason("agent " + std::to_string(r.agent) + " rejoined");
      session_->send_control(c);
    }
    progress.clear();  // partial sums of abandoned rounds
    ++rollbacks_;
    const std::string what = "agent " + std::to_string(d.agent) +
                             " rejoined: every agent rolls back to round " +
                             std::to_string(d.round) + " (epoch " + std::to_string(d.epoch) + ")";
    if (monitor)
      monitor->event(what, now);
    else
      std::cerr << "tessera-coordinator: " << what << "\n";
  }

  void write_summary(const coordinator::RunStructure& rs,
                     const coordinator::PartitionStepResult& part,
                     const std::vector<std::uint64_t>& bytes, std::uint32_t rounds,
                     double total_ms) {
    std::uint64_t total_bytes = 0;
    for (auto b : bytes) total_bytes += b;
    const auto final_value = [&](double v) {
      return have_final_report_ ? std::optional<double>(v) : std::nullopt;
    };
    // Mean wall time of one round (status of round k to status of round k+1), or null.
    const double rounds_ms = last_status_ms_ - first_status_ms_;
    cli::JsonObject j;
    j.add("algorithm", a_.algorithm.empty() ? "irbcd" : a_.algorithm)
        .add("init", a_.init)
        .add("graph", a_.graph_name)
        .add("poses", rs.num_poses)
        .add("edges", rs.num_measurements)
        .add("d", rs.d)
        .add("rank", static_cast<long long>(a_.rank ? a_.rank : 5))
        .add("iterations", static_cast<long long>(rounds))
        .add("grad_norm", final_value(final_grad_norm_))
        .add("cost", final_value(final_cost_))
        .add("certified",
             certificate_ ? std::optional<bool>(certificate_->certified) : std::nullopt)
        .add("wall_s", total_ms / 1000.0)
        .add("restarts", static_cast<long long>(final_restarts_))
        .add("bytes_exchanged", static_cast<long long>(total_bytes))
        .add("rollbacks", static_cast<long long>(rollbacks_))
        .add("run_id", a_.net.session.run_id)
        .add("domain", static_cast<long long>(session_->domain()))
        .add("agents", static_cast<long long>(a_.agents))
        .add("dim", rs.d)
        .add("num_poses", rs.num_poses)
        .add("num_measurements", rs.num_measurements)
        .add("partition", a_.partition)
        .add("cut_edges", part.cut_edges)
        .add("rounds", static_cast<long long>(rounds))
        .add("discovery_ms", discovery_ms_)
        .add("partition_ms", part.ms)
        .add("solve_ms", solve_ms_)
        .add("rounds_ms", rounds_ms)
        .add("ms_per_round", completed_statuses_ > 1
                                 ? std::optional<double>(rounds_ms / (completed_statuses_ - 1))
                                 : std::nullopt)
        .add("total_ms", total_ms)
        .add("bytes_sent", std::vector<std::size_t>(bytes.begin(), bytes.end()))
        .add("hosts", rs.hosts);
    if (loss_.epoch > 0) {  // the permanent-loss record (docs/fault-tolerance.md)
      cli::JsonObject f;
      std::vector<std::size_t> lost(loss_.lost.begin(), loss_.lost.end());
      std::vector<std::size_t> survivors(loss_.expected.begin(), loss_.expected.end());
      f.add("kind", "lost_for_good")
          .add("lost_agents", lost)
          .add("round", static_cast<long long>(loss_.last_round))
          .add("survivors", survivors)
          .add("moved_poses", loss_.moved_poses)
          .add("cut_edges_after", loss_.cut_edges)
          .add("repartition_at_s", loss_.at_ms / 1000.0)
          .add("epoch", static_cast<long long>(loss_.epoch));
      j.add("fault", f);
    } else {
      j.add_null("fault");
    }
    if (certificate_) {
      j.add("min_eigenvalue", certificate_->min_eigenvalue)
          .add("certificate_rounds", static_cast<long long>(certificate_->rounds))
          .add("final_rank", static_cast<long long>(certificate_->final_rank));
      if (certificate_bytes_)
        j.add("certificate_bytes", static_cast<long long>(certificate_bytes_->certificate))
            .add("escape_bytes", static_cast<long long>(certificate_bytes_->escape))
            .add("escape_rounds", static_cast<long long>(certificate_bytes_->escape_rounds));
    } else {
      j.add_null("min_eigenvalue").add_null("certificate_rounds");
      j.add("final_rank", static_cast<long long>(a_.rank ? a_.rank : 5));
    }
    cli::write_output(a_.summary, j.str());
  }

  CoordinatorArgs a_;
  SignalWatcher& signals_;
  std::unique_ptr<Session> session_;
  double discovery_ms_ = 0, solve_ms_ = 0;
  double first_status_ms_ = 0, last_status_ms_ = 0;  // completions of round statuses
  std::uint32_t completed_statuses_ = 0;
  // From agent 0's final report (agent/round_loop.hpp kFinalReportPhase).
  double final_cost_ = 0, final_grad_norm_ = 0;
  std::uint32_t final_restarts_ = 0;
  bool have_final_report_ = false;
  // From agent 0's certificate reports (certification only).
  struct CertificateReport {
    bool certified;
    double min_eigenvalue, rounds, final_rank;
  };
  struct CertificateTraffic {
    double certificate, escape, escape_rounds;
  };
  std::optional<CertificateReport> certificate_;
  std::optional<CertificateTraffic> certificate_bytes_;
  std::uint32_t rollbacks_ = 0;  // coordinated rollbacks (agents that rejoined)
  // Permanent loss: the assignment in force and what the re-partition did (for the summary).
  wire::PartitionAssignment base_assignment_;
  struct {
    std::uint32_t epoch = 0;              // > 0 after a re-partition for the survivors
    std::vector<std::uint32_t> owner;     // agent of every pose, as now assigned
    std::vector<std::uint32_t> expected;  // agents whose final estimates count
    std::vector<std::uint32_t> lost;
    std::uint32_t last_round = 0;  // last round status seen before the loss
    std::size_t moved_poses = 0, cut_edges = 0;
    double at_ms = 0;  // since the rounds started
    std::map<std::uint32_t, std::chrono::steady_clock::time_point> second;  // survivors lost
    std::chrono::steady_clock::time_point t_run;
  } loss_;
};

}  // namespace

int main(int argc, char** argv) {
  SignalWatcher signals;  // first: every thread created later inherits the blocked signals
  std::vector<std::string> argv_list(argv + 1, argv + argc);
  for (const auto& a : argv_list)
    if (a == "--help" || a == "-h") {
      std::printf(kHelp, cli::session_options_help(cli::SessionArgsFor::kProcess).c_str());
      return kExitOk;
    }
  CoordinatorArgs args;
  try {
    args = parse(argv_list);
  } catch (const InputError& e) {
    std::cerr << "tessera-coordinator: error: " << e.what() << "\n";
    return kExitBadInput;
  }
  Coordinator c(args, signals);
  return c.run();
}
