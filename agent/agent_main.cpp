// tessera-agent: one robot's process in a distributed run. Thin over core/ (graph I/O,
// the round protocol) and transport/ (DDS). See docs/dds-runtime.md.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "agent/agent_checkpoint.hpp"
#include "agent/checkpoint_keeper.hpp"
#include "agent/dds_channel.hpp"
#include "agent/initialization_stage.hpp"
#include "agent/local_dump.hpp"
#include "agent/local_share.hpp"
#include "agent/robot_file.hpp"
#include "agent/rejoin.hpp"
#include "agent/round_loop.hpp"
#include "agent/survivor_exchange.hpp"
#include "arguments.hpp"
#include "distributed/checkpoint_file.hpp"
#include "distributed/distributed_solver.hpp"
#include "distributed/replica_plan.hpp"
#include "io/g2o_reader.hpp"
#include "problem/lifting.hpp"
#include "session_args.hpp"
#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"
#include "transport/session.hpp"
#include "transport/signal_watcher.hpp"
#include "transport/transport_error.hpp"
#include "util/input_error.hpp"

using namespace tessera;
using namespace tessera::transport;

namespace {

// %s: the shared DDS session options (cli/session_args.hpp).
constexpr const char* kHelp = R"(usage: tessera-agent --graph FILE --robots N --id I [options]

One agent (robot) of a distributed Tessera run. Reads robot I's share of a multi-robot
g2o file (its contiguous poses [I n/N, (I+1) n/N) and the measurements starting there),
announces its graph structure to the coordinator, hands measurements and initial poses
to the agents that own them after the partition (peer to peer: the coordinator never sees
measurement values), runs the round protocol and sends its final poses to the coordinator.

options:
  --graph FILE       g2o file of the whole multi-robot graph (required), or a file with only
                     this robot's data (it starts with '# tessera-robot poses BEGIN END';
                     written by tessera generate --split; see docs/dds-runtime.md)
  --robots N         number of robots = agents of the run (required)
  --id I             this agent's id, 0..N-1 (required)
  --round-timeout S  bound on each wait for a peer's message during the rounds (default 600)
  --output FILE      write this agent's final poses as g2o VERTEX lines
  --dump-local FILE  write the local problem after the hand-off (text; see docs/dds-runtime.md)
  --checkpoint-dir DIR  keep this agent's checkpoint in DIR (one folder per run). Started
                     again with the same options after a crash, the agent finds it there and
                     rejoins the run (the coordinator needs --rejoin-timeout); removed when
                     the run completes. A damaged checkpoint is an error naming the file.
  --checkpoint-every K  write the checkpoint every K rounds (default 1)
  --udp-only         talk UDP only, no shared memory (implied by --checkpoint-dir): for runs
                     that survive a SIGKILLed peer (tessera launch --on-agent-loss continue)
  --verbose          print each phase
  --help             this text

DDS session options (shared with tessera-coordinator and tessera launch):
%s
exit codes: 0 done, 1 the run failed (lost peer, abort, timeout), 2 bad options or input,
128+signal when interrupted (SIGINT 130, SIGTERM 143).
)";

struct AgentArgs {
  std::string graph;
  std::uint32_t robots = 0;
  std::uint32_t id = 0;
  cli::SessionArgs net;  ///< run id, domain, lease, peers, --timeout (cli/session_args.hpp)
  double round_timeout_s = 600;
  std::string output;
  std::string dump_local;
  std::string checkpoint_dir;
  int checkpoint_every = 1;
  bool udp_only = false;
  bool verbose = false;
};

AgentArgs parse(const std::vector<std::string>& argv) {
  cli::Arguments args(
      argv,
      cli::with_session_options({"graph", "robots", "id", "round-timeout", "output", "dump-local",
                                 "checkpoint-dir", "checkpoint-every"},
                                cli::SessionArgsFor::kProcess),
      {"verbose", "help", "udp-only"});
  if (!args.positional().empty())
    throw InputError("unexpected argument '" + args.positional().front() + "' (see --help)");
  AgentArgs a;
  if (!args.has("graph")) throw InputError("option --graph is required (see --help)");
  if (!args.has("robots")) throw InputError("option --robots is required (see --help)");
  if (!args.has("id")) throw InputError("option --id is required (see --help)");
  a.graph = *args.get("graph");
  long robots = args.get_long("robots", 0), id = args.get_long("id", 0);
  if (robots < 1 || robots > 1000) throw InputError("option --robots: must be 1..1000");
  if (id < 0 || id >= robots)
    throw InputError("option --id: must be 0.." + std::to_string(robots - 1));
  a.robots = static_cast<std::uint32_t>(robots);
  a.id = static_cast<std::uint32_t>(id);
  a.net = cli::parse_session_args(args, cli::SessionArgsFor::kProcess);
  a.round_timeout_s = args.get_double("round-timeout", a.round_timeout_s);
  if (!(a.round_timeout_s > 0)) throw InputError("option --round-timeout: must be positive");
  a.output = args.get_or("output", "");
  a.dump_local = args.get_or("dump-local", "");
  a.checkpoint_dir = args.get_or("checkpoint-dir", "");
  a.udp_only = args.has("udp-only");
  a.checkpoint_every = static_cast<int>(args.get_long("checkpoint-every", 1));
  agent::CheckpointOptions{a.checkpoint_dir, a.checkpoint_every}.validate();
  a.verbose = args.has("verbose");
  return a;
}

class Agent {
 public:
  Agent(const AgentArgs& a, SignalWatcher& signals) : a_(a), signals_(signals) {
    tag_ = "tessera-agent[" + std::to_string(a.id) + "]";
  }

  int run() {
    // A checkpoint of this run in --checkpoint-dir means this process is a restart: rejoin.
    if (!a_.checkpoint_dir.empty()) {
      const std::string path = agent::checkpoint_path(a_.checkpoint_dir, a_.id);
      if (access(path.c_str(), F_OK) == 0) {
        try {
          rejoin_ = agent::load_checkpoint(path, a_.net.session.run_id, a_.id, a_.robots);
        } catch (const CheckpointError& e) {
          std::cerr << tag_ << ": error: " << e.what() << "\n";
          return kExitBadInput;
        }
        std::cerr << tag_ << ": rejoining run '" << a_.net.session.run_id << "' from checkpoint "
                  << path << " (rounds " << rejoin_->snapshots.front().round << ".."
                  << rejoin_->snapshots.back().round << ")\n";
        // The others drop our previous incarnation after one lease; joining earlier would
        // look like two processes claiming this id.
        std::this_thread::sleep_for(Seconds(1.5 * a_.net.session.lease_s));
      }
    }
    SessionOptions so = a_.net.session;
    // An agent meant to survive a SIGKILL talks UDP only (see transport/qos.hpp).
    so.shared_memory = a_.checkpoint_dir.empty() && !a_.udp_only;
    so.coordinator = false;
    so.agent_id = a_.id;
    so.num_agents = a_.robots;
    so.verbose = a_.verbose;
    try {
      session_ = std::make_unique<Session>(so);
    } catch (const InputError& e) {
      std::cerr << tag_ << ": error: " << e.what() << "\n";
      return kExitBadInput;
    } catch (const std::exception& e) {
      std::cerr << tag_ << ": error: " << e.what() << "\n";
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
    } catch (const agent::RunStopped&) {
      auto stop = s.mailroom().stop_info().value_or(StopInfo{kExitRunFailed, "stopped", false});
      code = leave(stop.exit_code, stop.reason, !stop.remote);
    } catch (const std::exception& e) {
      // A RunStopped may hide behind another error raised while stopping: prefer the cause.
      if (auto stop = s.mailroom().stop_info())
        code = leave(stop->exit_code, stop->reason, !stop->remote);
      else
        code = leave(kExitRunFailed, e.what(), true);
    }
    signals_.stop();  // the callback refers to the session
    s.close();
    return code;
  }

 private:
  void log(const std::string& what) {
    if (a_.verbose) std::cerr << tag_ << ": " << what << "\n";
  }

  // Prints the error and tells the other processes (ABORT), then waits briefly so the ABORT
  // reaches them before this participant disappears. `own` false: the reason came from
  // another process (relayed as is, so peers that never heard the original still learn the
  // cause instead of only seeing this agent leave).
  int leave(int code, const std::string& why, bool own) {
    std::cerr << tag_ << ": error: " << why << "\n";
    try {
      session_->send_control(wire::CONTROL_ABORT,
                             own ? "agent " + std::to_string(a_.id) + ": " + why : why);
      // An agent with bad input fails at start-up, typically before it has discovered
      // everyone: wait longer for peers still starting so they learn why.
      const Seconds linger(std::min(3.0, a_.net.timeout_s));
      session_->linger_for_control(linger, code == kExitBadInput ? linger : Seconds(1.0));
    } catch (const std::exception&) {
      // Leaving anyway: the others notice this participant disappear.
    }
    return code;
  }

  void phases() {
    const auto t0 = std::chrono::steady_clock::now();
    if (rejoin_) {
      solve(rejoin_->local, t0);
    } else {
      agent::AgentLocalData local = fresh_start();
      solve(local, t0);
    }
  }

  // Steps 1-6 of a run: share, announcement, assignment, readiness, initialisation, hand-off.
  agent::AgentLocalData fresh_start() {
    Session& s = *session_;
    Mailroom& room = s.mailroom();

    // 1. Our share of the graph: robot I's part of the whole file, or the robot's own file.
    if (agent::is_robot_file(a_.graph)) {
      share_ = agent::read_robot_file(a_.graph, a_.id);  // n comes with the assignment
    } else {
      PoseGraph graph = read_g2o(a_.graph);
      share_ = agent::robot_share(graph, a_.id, a_.robots);
    }
    log("read " + a_.graph + ": poses [" + std::to_string(share_.begin) + ", " +
        std::to_string(share_.end) + ") of " + std::to_string(share_.num_poses) + ", " +
        std::to_string(share_.measurements.size()) + " measurements");

    // 2. Announce the structure (endpoints only).
    wire::AgentAnnouncement ann;
    ann.run_id(a_.net.session.run_id);
    ann.agent_id(a_.id);
    ann.num_agents(a_.robots);
    ann.host(host_name());
    ann.pid(static_cast<std::uint32_t>(getpid()));
    ann.dim(static_cast<std::uint32_t>(share_.d));
    ann.num_poses(static_cast<std::uint32_t>(share_.num_poses));
    ann.pose_begin(share_.begin);
    ann.pose_end(share_.end);
    for (const Measurement& m : share_.measurements) {
      ann.edge_i().push_back(static_cast<std::uint32_t>(m.i));
      ann.edge_j().push_back(static_cast<std::uint32_t>(m.j));
    }
    ann.edge_index(share_.measurement_index);
    s.publish(ann);
    log("announced");

    // 3. The assignment.
    wire::PartitionAssignment asg;
    WaitStatus got = s.assignments().take(Seconds(a_.net.timeout_s), &asg);
    expect_ready(got, room, a_.net.timeout_s, "the partition assignment from the coordinator",
                 s.peers_ever_seen() == 0
                     ? "no process of run '" + a_.net.session.run_id + "' seen on domain " +
                           std::to_string(s.domain()) + " (is the coordinator running?)"
                     : "");
    check_assignment(asg);
    rejoin_enabled_ = asg.rejoin_timeout_s() > 0;
    loss_.replicas = asg.replicas();
    loss_.replica_every = std::max<std::uint32_t>(1, asg.replica_every());
    log("assignment received (" +
        std::to_string(std::count(asg.owner().begin(), asg.owner().end(), a_.id)) +
        " poses owned)");

    // 4. Everyone's endpoints matched before any volatile agent-to-agent message.
    std::string missing;
    expect_ready(s.ready_barrier(Seconds(a_.net.timeout_s), &missing), room, a_.net.timeout_s,
                 "the other processes to be ready", missing);
    log("all processes ready");

    // 5. Initial poses of our share (agent/initialization_stage.hpp), before they move.
    if (asg.edge_i().size() != asg.edge_j().size())
      throw RunFailure(kExitRunFailed, "the assignment's structure arrays differ in length");
    std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;
    structure.reserve(asg.edge_i().size());
    for (std::size_t e = 0; e < asg.edge_i().size(); ++e) {
      if (asg.edge_i()[e] >= share_.num_poses || asg.edge_j()[e] >= share_.num_poses)
        throw RunFailure(kExitRunFailed, "the assignment's structure names a pose out of range");
      structure.emplace_back(asg.edge_i()[e], asg.edge_j()[e]);
    }
    agent::DdsProtocolChannel channel(s);
    {
      agent::InitializationResult init =
          agent::run_initialization_stage(share_, a_.id, a_.robots, structure, asg.initialization(),
                                          a_.graph, channel, a_.round_timeout_s);
      share_.initial = std::move(init.poses);
      log("initialisation '" + init.method + "' done in " +
          std::to_string(static_cast<long>(init.seconds * 1000)) + " ms");
    }

    // 6. Hand-off, peer to peer: exactly one message to every other agent.
    for (std::uint32_t b = 0; b < a_.robots; ++b) {
      if (b == a_.id) continue;
      agent::HandoffPlan plan = agent::plan_handoff(share_, asg.owner(), b);
      s.publish(to_wire_handoff(a_.net.session.run_id, a_.id, b, share_.d, plan.measurements,
                                plan.measurement_index, plan.poses));
    }
    const std::size_t others = a_.robots - 1;
    auto senders_missing = [&](const std::deque<wire::MeasurementHandoff>& q) {
      std::set<std::uint32_t> have;
      for (const auto& h : q) have.insert(h.sender());
      std::string out;
      for (std::uint32_t b = 0; b < a_.robots; ++b)
        if (b != a_.id && !have.count(b))
          out += (out.empty() ? "agent " : ", agent ") + std::to_string(b);
      return out;
    };
    std::string absent;
    expect_ready(s.handoffs().wait_for(
                     [&](const auto& q) {
                       absent = senders_missing(q);
                       return q.size() >= others && absent.empty();
                     },
                     Seconds(a_.net.timeout_s)),
                 room, a_.net.timeout_s, "measurement hand-offs", "none yet from " + absent);
    std::vector<agent::ReceivedHandoff> received;
    for (auto& w : s.handoffs().take_all()) {
      HandoffContent c = from_wire(w);
      received.push_back({w.sender(), std::move(c.measurements), std::move(c.measurement_index),
                          std::move(c.poses)});
    }
    agent::RunOptions ro;
    ro.algorithm = asg.algorithm();
    ro.initialization = asg.initialization();
    ro.rank = asg.rank();
    ro.max_rounds = asg.max_rounds();
    ro.grad_norm_tolerance = asg.grad_norm_tolerance();
    ro.relative_cost_tolerance = asg.relative_cost_tolerance();
    ro.seed = asg.seed();
    ro.certify = asg.certify();
    agent::AgentLocalData local =
        agent::assemble_local(share_, asg.owner(), a_.id, a_.robots, std::move(received), ro);
    share_ = agent::RobotShare();
    local.structure = std::move(structure);
    log("hand-off complete: " + std::to_string(local.owned.size()) + " poses, " +
        std::to_string(local.measurements.size()) + " measurements");
    if (!a_.dump_local.empty()) agent::write_local_dump(local, a_.dump_local);
    return local;
  }

  // Steps 7-8: the rounds (resumed from a snapshot on every coordinated rollback), the final
  // estimate, and the wait for the coordinator's FINISHED.
  void solve(const agent::AgentLocalData& local, std::chrono::steady_clock::time_point t0) {
    Session& s = *session_;
    // 7. THE SEAM: core's round protocol over DDS.
    agent::DdsProtocolChannel channel(s);
    agent::CheckpointKeeper keeper(a_.net.session.run_id, local,
                                   {a_.checkpoint_dir, a_.checkpoint_every});
    std::optional<ProtocolSnapshot> from;  // a copy: the keeper replaces its entries
    // With a rejoin window the coordinator arbitrates lost agents (it waits for a restart,
    // then orders a rollback, or gives up and aborts the run): do not stop on one.
    if (rejoin_enabled_ || rejoin_ || loss_.replicas > 0) s.set_agent_loss_tolerated(true);
    const agent::AgentLocalData* cur = &local;  // the survivors' new block after a re-partition
    if (loss_.replicas > 0 && !rejoin_) start_replication(local, channel);
    if (rejoin_) {
      keeper.adopt(rejoin_->snapshots);
      const agent::RollbackRequested order =
          agent::request_rejoin(s, a_.id, rejoin_->snapshots, a_.net.timeout_s);
      from = agent::prepare_rollback(s, keeper, order, a_.net.timeout_s);
      log("rejoined: resuming at round " + std::to_string(order.round) + ", epoch " +
          std::to_string(order.epoch));
    }
    agent::RoundLoopHooks hooks;
    hooks.on_round = [&](const ProtocolSnapshot& snap) {
      if (cur == &local) keeper.on_round(snap);
      if (loss_.replicas > 0) on_round_replicate(*cur, snap);
    };
    for (;;) {
      try {
        hooks.resume_from = from ? &*from : nullptr;
        finish(*cur, agent::run_round_loop(*cur, channel, a_.round_timeout_s, hooks), t0);
        break;
      } catch (const agent::RepartitionRequested& order) {
        if (loss_.replicas == 0 || cur != &local)
          throw RunFailure(kExitRunFailed, std::string(order.what()) +
                                               ": this run does not replicate for a second loss");
        loss_.taken = take_over(local, order.assignment);
        cur = &*loss_.taken;
        from.reset();
      } catch (const agent::RollbackRequested& order) {
        std::cerr << tag_ << ": " << order.what() << ": resuming from the snapshot of round "
                  << order.round << "\n";
        from = agent::prepare_rollback(s, keeper, order, a_.net.timeout_s);
      }
    }
    if (!a_.checkpoint_dir.empty()) {
      const auto& cs = keeper.stats();
      char buf[200];
      std::snprintf(buf, sizeof(buf),
                    "%s: checkpoints: %llu written, %.1f ms in total (%.2f ms each), %llu bytes "
                    "each\n",
                    tag_.c_str(), static_cast<unsigned long long>(cs.writes), cs.write_s * 1e3,
                    cs.writes ? cs.write_s * 1e3 / static_cast<double>(cs.writes) : 0.0,
                    static_cast<unsigned long long>(cs.last_bytes));
      std::cerr << buf;
      std::remove(keeper.path().c_str());  // the run is complete: nothing to rejoin
    }
  }

  void finish(const agent::AgentLocalData& local, const agent::RoundLoopResult& result,
              std::chrono::steady_clock::time_point t0) {
    Session& s = *session_;
    Mailroom& room = s.mailroom();
    if (result.poses.size() != local.owned.size())
      throw RunFailure(kExitRunFailed, "the round loop returned " +
                                           std::to_string(result.poses.size()) + " poses for " +
                                           std::to_string(local.owned.size()) + " owned poses");
    {
      char line[200];
      std::snprintf(line, sizeof(line),
                    "round loop done: %u round(s) in %.3f s, rounding %.3f s (%u CG iterations), "
                    "%llu messages, %llu write retries",
                    result.rounds, result.solve_s, result.rounding_s, result.translation_iterations,
                    static_cast<unsigned long long>(s.stats().messages_sent),
                    static_cast<unsigned long long>(s.stats().write_retries));
      log(line);
    }
    if (!a_.output.empty())
      agent::write_vertices_g2o(local.owned, result.poses, local.d, a_.output);

    // 8. Final estimate to the coordinator; leave when it has the merged result.
    wire::FinalEstimate fin;
    fin.run_id(a_.net.session.run_id);
    fin.sender(a_.id);
    fin.dim(static_cast<std::uint32_t>(local.d));
    fin.rounds(result.rounds);
    fin.pose_ids(local.owned);
    for (const Pose& p : result.poses) append_pose(fin.pose_data(), p);
    fin.bytes_sent(s.stats().bytes_sent + serialized_size(fin));
    fin.epoch(s.epoch());
    s.publish(fin);
    // Until FINISHED, a rollback (another agent rejoined) means doing the rounds again.
    const auto wait_start = std::chrono::steady_clock::now();
    for (;;) {
      const WaitStatus st = s.wait_finished(Seconds(0.2));
      if (st == WaitStatus::kReady) break;
      if (auto order = agent::take_rollback(s)) throw *order;
      if (auto a = agent::take_reassignment(s)) throw agent::RepartitionRequested(std::move(*a));
      const double waited =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wait_start).count();
      if (st == WaitStatus::kStopped || waited > a_.net.timeout_s)
        expect_ready(st, room, a_.net.timeout_s, "the coordinator to confirm the merged result");
    }
    s.set_peer_loss_fatal(false);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "%s: done: %zu poses, %zu measurements, %u round(s), cost %.12g, %llu bytes "
                  "sent, %.2f s\n",
                  tag_.c_str(), local.owned.size(), local.measurements.size(), result.rounds,
                  result.cost, static_cast<unsigned long long>(s.stats().bytes_sent), secs);
    std::cerr << buf;
  }

  void check_assignment(const wire::PartitionAssignment& asg) {
    if (share_.num_poses == 0) agent::adopt_num_poses(share_, asg.num_poses(), a_.graph);
    auto mismatch = [&](const std::string& what) {
      throw RunFailure(kExitBadInput,
                       "the coordinator's assignment does not fit this agent: " + what);
    };
    if (asg.num_agents() != a_.robots)
      mismatch("it is for " + std::to_string(asg.num_agents()) +
               " agents, this agent was started with --robots " + std::to_string(a_.robots));
    if (asg.num_poses() != share_.num_poses || asg.owner().size() != share_.num_poses)
      mismatch("it has " + std::to_string(asg.owner().size()) + " poses, " + a_.graph + " has " +
               std::to_string(share_.num_poses));
    if (asg.dim() != static_cast<std::uint32_t>(share_.d))
      mismatch("dimension " + std::to_string(asg.dim()) + " vs " + std::to_string(share_.d));
    for (std::uint32_t o : asg.owner())
      if (o >= a_.robots) mismatch("owner " + std::to_string(o) + " is not an agent id");
  }

  AgentArgs a_;
  SignalWatcher& signals_;
  std::string tag_;
  std::unique_ptr<Session> session_;
  agent::RobotShare share_;
  // Permanent loss (agent/survivor_takeover.hpp): replication and take-over state.
  struct LossState {
    std::uint32_t replicas = 0, replica_every = 10;
    std::vector<std::uint32_t> holders;  // who keeps this agent's replica
    agent::ReplicaStore store;           // replicas this agent keeps
    Eigen::MatrixXd Y;                   // latest lifted poses (consistent point)
    std::uint32_t round = 0;
    std::optional<agent::AgentLocalData> taken;  // the new block after a re-partition
  } loss_;

  void start_replication(const agent::AgentLocalData& local, agent::DdsProtocolChannel& channel) {
    std::vector<std::uint32_t> owner = local.owner;
    loss_.holders =
        replica_holders(local.structure, owner, local.num_agents, loss_.replicas)[local.agent_id];
    const DistributedOptions dummy;
    loss_.Y = lift_poses(local.initial,
                         static_cast<int>(local.options.rank ? local.options.rank : dummy.rank));
    agent::send_problem_replicas(*session_, local, a_.id, loss_.Y, loss_.holders);
    channel.set_intercept([this](const ProtocolMessage& m) {
      const auto* b = std::get_if<PoseBlockMessage>(&m);
      if (!b || b->phase != agent::kReplicaPhase) return false;
      loss_.store.absorb_poses(*b);
      return true;
    });
    log("replicating to agent(s) " + join_ids(loss_.holders) + " every " +
        std::to_string(loss_.replica_every) + " rounds");
  }

  void on_round_replicate(const agent::AgentLocalData& local, const ProtocolSnapshot& snap) {
    loss_.Y = snap.Y;
    loss_.round = static_cast<std::uint32_t>(snap.round);
    // Replicas only in the first epoch: a second loss is not covered (see the docs).
    if (!loss_.taken && !loss_.holders.empty() &&
        static_cast<std::uint32_t>(snap.round) % loss_.replica_every == 0) {
      PoseBlockMessage m =
          agent::replica_block(local.agent_id, loss_.round, local.d, local.owned, snap.Y);
      session_->send(OutgoingMessage{m, false, loss_.holders});
    }
  }

  agent::AgentLocalData take_over(const agent::AgentLocalData& local,
                                  const wire::PartitionAssignment& asg) {
    Session& s = *session_;
    agent::absorb_problem_replicas(s, loss_.store);
    const agent::Reassignment r = agent::reassignment_of(asg, local.owner);
    std::cerr << tag_ << ": agent(s) " << join_ids(r.lost)
              << " lost for good: taking over the re-partition (epoch " << r.epoch << ", "
              << r.survivors.size() << " survivors)\n";
    agent::TakeoverSource src;
    src.self = a_.id;
    src.local = &local;
    src.Y = loss_.Y;
    src.round = loss_.round;
    src.replicas = &loss_.store;
    agent::AgentLocalData next = agent::exchange_takeover(s, src, r, a_.net.timeout_s);
    s.set_epoch(r.epoch, next.agent_id);
    log("take-over complete: " + std::to_string(next.owned.size()) + " poses, " +
        std::to_string(next.measurements.size()) + " measurements, protocol id " +
        std::to_string(next.agent_id) + " of " + std::to_string(next.num_agents));
    return next;
  }

  static std::string join_ids(const std::vector<std::uint32_t>& ids) {
    std::string out;
    for (auto k : ids) out += (out.empty() ? "" : ", ") + std::to_string(k);
    return out;
  }
  std::optional<agent::AgentCheckpoint> rejoin_;  // set when restarted from a checkpoint
  bool rejoin_enabled_ = false;                   // the coordinator waits for lost agents
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
  AgentArgs args;
  try {
    args = parse(argv_list);
  } catch (const InputError& e) {
    std::cerr << "tessera-agent: error: " << e.what() << "\n";
    return kExitBadInput;
  }
  Agent agent(args, signals);
  return agent.run();
}
