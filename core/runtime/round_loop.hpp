#pragma once
// THE SEAM between the DDS runtime and core's round protocol.
//
// After the hand-off, an agent holds its local problem (AgentLocalData) and a
// ProtocolChannel that delivers core ProtocolMessages to and from the other agents. The
// runtime calls run_round_loop() once and publishes the poses it returns as this agent's
// final estimate. Nothing here knows about DDS: the same function can be driven by an
// in-process channel in tests.
//
// run_round_loop() runs core's agent (AgentState + RoundProtocol, configured exactly as the
// in-process engine configures it) and then rounds the final iterate to SE(d) without a
// central step: the rotation rounding from a summed Gram matrix, the optimal translations
// by a distributed preconditioned conjugate gradient on the translation Laplacian.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/graph/measurement.hpp>
#include <tessera/graph/pose.hpp>
#include <tessera/protocol/awaited_messages.hpp>
#include <tessera/protocol/messages.hpp>
#include <tessera/robust/robust_options.hpp>
#include <utility>
#include <vector>

#include "runtime/agent_report.hpp"

namespace tessera {
struct ProtocolSnapshot;  // distributed/protocol_snapshot.hpp
}

namespace tessera::agent {

/// Algorithm options of the run as published by the coordinator (simple fields).
struct RunOptions {
  std::string algorithm;           ///< Solver name ("" = core's default).
  std::string initialization;      ///< e.g. "distributed" ("" = core's default).
  std::uint32_t rank = 0;          ///< r (0 = d).
  std::uint32_t max_rounds = 0;    ///< 0 = core's default.
  double grad_norm_tolerance = 0;  ///< 0 = core's default.
  double relative_cost_tolerance = 0;
  std::uint64_t seed = 1;
  bool certify = false;  ///< Certified sequence (solve -> certify -> escape ...), core's defaults.
  std::uint32_t coarse_every = 0;  ///< Coarse correction every this many rounds; 0 = off.
  /// The coarse space: 0 = one rigid motion per block; K > 0 = the smoothed space with K
  /// pieces per block and coarse_smoothing smoothing steps (coarse_space.hpp).
  std::uint32_t coarse_aggregates = 0;
  std::uint32_t coarse_smoothing = 1;
  /// Newton refinement after the rounds (newton_refine.hpp) and its tolerances (0 = core's).
  std::string refine = "auto";  ///< "none", "newton" or "auto" (set_refine_mode).
  double refine_grad_tol = 0;
  double refine_rel_tol = 0;
  /// Who factors the refinement's interface matrix (set_sigma_mode): "one" (agent 0, which
  /// sends its factor), "solve" (agent 0, which sends its solves), "every", or ""
  /// (core's default).
  std::string refine_sigma;
  /// BlockUpdateOptions::max_factor_entries (0 = core's default; runtime/team_memory.hpp).
  std::uint64_t max_factor_entries = 0;
  /// BlockUpdateOptions::tangent_split_dots (`--tangent-dots split|sequential`): the tangent
  /// factor's backward dot products as four partial sums (core's default) or CHOLMOD's sequential
  /// sums. Changes the iterates' last bits, so every agent must use the run's one value.
  bool tangent_split_dots = true;
  /// Robust solve (`--robust`; robust/gnc_agent.hpp runs it): kind none = plain least squares.
  RobustOptions robust;
  /// GNC starts from the known inliers' distributed initialization when they connect the poses
  /// (GncDistributedOptions::known_inlier_start; off when --init is given).
  bool gnc_known_start = true;
  /// GncDistributedOptions::cluster_probes (0 = none; `--gnc-cluster-probes`).
  int gnc_cluster_probes = 0;
};

/// Everything one agent knows after the hand-off.
struct AgentLocalData {
  std::uint32_t agent_id = 0;
  std::uint32_t num_agents = 1;
  int d = 0;
  std::size_t num_poses = 0;         ///< n of the whole graph.
  std::vector<std::uint32_t> owner;  ///< Owner agent of every pose 0..n-1.
  std::vector<std::uint32_t> owned;  ///< Poses this agent optimizes, ascending.
  /// Every measurement with at least one endpoint in `owned`, in the order of the original
  /// file (measurement_index is the position in that file), so sums can follow the same
  /// order as the in-process engine.
  std::vector<Measurement> measurements;
  std::vector<std::uint64_t> measurement_index;
  /// Initial poses of `owned` (same order), from the initialisation stage.
  std::vector<Pose> initial;
  /// A robust run's second candidate start of `owned` (same order), the known inliers'
  /// initialization (GncAgentInput::Y0_known), or empty.
  std::vector<Pose> known_initial;
  /// When not empty: the lifted starting point of `owned` (r x (d+1)m, same order), used
  /// instead of lifting `initial` (a run continued by survivors after a permanent loss).
  Eigen::MatrixXd lifted_start;
  /// Endpoints (i, j) of every measurement of the whole graph, no values: with `owner`
  /// enough for core's make_block_layout, so every agent builds the same layout (neighbours,
  /// public poses, colouring).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;
  /// Empty, or one flag per measurement of `structure`: true = a known inlier by the input's
  /// own flag (a dpgo CSV file's is_known_inlier; the coordinator's assignment carries them).
  std::vector<bool> known_inlier;
  RunOptions options;
};

/// Raised by a channel when the run is stopping (lost peer, abort, signal): the round loop
/// must unwind; the runtime reports the reason.
class RunStopped : public std::runtime_error {
 public:
  explicit RunStopped(const std::string& why) : std::runtime_error(why) {}
};

/// Raised by a channel when the coordinator orders a coordinated rollback (an agent was
/// restarted and rejoins): every agent abandons its current round and resumes from its
/// snapshot of `round`; messages of earlier epochs are discarded from then on.
class RollbackRequested : public std::runtime_error {
 public:
  RollbackRequested(std::uint32_t round, std::uint32_t epoch, std::uint32_t rejoined_agent)
      : std::runtime_error("rollback to round " + std::to_string(round) + " (agent " +
                           std::to_string(rejoined_agent) + " rejoined)"),
        round(round),
        epoch(epoch),
        agent(rejoined_agent) {}
  std::uint32_t round, epoch, agent;
};

/// How the round loop talks to the other agents.
class ProtocolChannel {
 public:
  virtual ~ProtocolChannel() = default;
  /// Sends to every agent (broadcast) or to the listed recipients. Never delivered back to
  /// the sender. Throws RunStopped / std::runtime_error when it cannot be delivered.
  virtual void send(const OutgoingMessage& message) = 0;
  /// The messages one protocol step emits, in order. A channel may pack messages for the same
  /// recipient into one delivery (the DDS channel: blocks to the status relay ride with the
  /// status); the default sends them one by one.
  virtual void send_all(const std::vector<OutgoingMessage>& messages);
  /// The next message for this agent in arrival order (FIFO per sender and message type;
  /// a block and a status from one sender may arrive in either order), or nullopt when
  /// none arrived within `timeout_s`. Throws RunStopped when the run is stopping.
  virtual std::optional<ProtocolMessage> receive(double timeout_s) = 0;
  /// receive() for a caller whose protocol step still needs `wake_after` messages (a lower
  /// bound, AgentProcess::messages_needed()): the channel may sleep until that many have
  /// arrived instead of waking for each one. Anything else that needs the caller (a stop, a
  /// rollback, a re-partition) and the timeout still end the wait at once.
  /// The default is receive(timeout_s).
  virtual std::optional<ProtocolMessage> receive_after(double timeout_s, std::size_t wake_after);
  /// receive() for a caller whose protocol step waits for exactly `awaited`
  /// (AgentProcess::awaited()): the channel may sleep until all of them have arrived; the
  /// message returned may be any queued one. Ends early as receive_after() does.
  /// The default is receive_after(timeout_s, awaited.senders.size()).
  virtual std::optional<ProtocolMessage> receive_awaiting(double timeout_s,
                                                          const AwaitedMessages& awaited);
  /// Sends one of agent 0's reports to the coordinator (agent_report.hpp); no agent receives
  /// it. Throws as send(). The default drops it: a run without a coordinator (in-process
  /// channels) has no one to read it.
  virtual void report(const AgentReport& report);
};

struct RoundLoopResult {
  std::vector<Pose> poses;  ///< Final (rounded) poses of `owned`, same order.
  std::uint32_t rounds = 0;
  std::uint32_t restarts = 0;
  std::string stop_reason;       ///< grad_norm, max_rounds or relative_decrease.
  double relaxation_cost = 0.0;  ///< f of the final lifted iterate (as every agent summed it).
  double grad_norm = 0.0;        ///< ||grad f|| there.
  double cost = 0.0;             ///< Objective of the rounded poses (whole graph, summed).
  std::uint32_t translation_iterations = 0;  ///< Distributed CG iterations of the rounding.
  /// Team interface poses of the rounding's exact translation solve; 0 = the CG ran.
  std::uint32_t rounding_interface_poses = 0;
  double solve_s = 0.0;     ///< Time in core's protocol.
  double rounding_s = 0.0;  ///< Time in the distributed rounding.
  /// Where the solve and rounding time went (seconds): waiting for messages, handing
  /// messages to the channel (serialising and writing), and the rest (this agent's math).
  double wait_s = 0.0, send_s = 0.0;
  /// Message steps of the rounding (every one waits for peers: rotations, CG, cost).
  std::uint32_t rounding_steps = 0;
  /// The stages after the rounds on this agent (seconds, summed over the stages of each kind;
  /// 0 where none ran): wall from the message whose handling began the stage to the one whose
  /// handling began the next, and of it waiting for messages; the refinements' own results
  /// (their parts' times and this agent's counts).
  double refine_wall_s = 0.0, refine_wait_s = 0.0;
  double certificate_wall_s = 0.0, certificate_wait_s = 0.0;
  std::vector<NewtonRefineResult> refines;
  // Certification (RunOptions::certify), identical on every agent; bytes summed over agents.
  std::optional<bool> certified;
  double min_eigenvalue = 0.0;
  DualBound certificate_bound;  ///< The last certificate's (dual_bound.hpp).
  std::uint32_t certificate_rounds = 0, escape_rounds = 0;
  std::uint64_t certificate_bytes = 0, escape_bytes = 0;
  std::uint32_t final_rank = 0;
  // Robust solve (RunOptions::robust): identical on every agent. `rounds` then counts every
  // solve (the GNC steps, the inlier passes, the final one) and `cost` is over the kept set.
  std::optional<RobustRunReport> robust;
};

/// Status phases of the messages the round loop adds after core's protocol (the distributed
/// rounding's reductions); agent 0's reports to the coordinator are AgentReports instead
/// (agent_report.hpp, ProtocolChannel::report).
constexpr std::uint32_t kRoundingPhaseBase = 100;

/// Optional recovery hooks of the round loop.
struct RoundLoopHooks {
  /// Called at every consistent point of the protocol (see RoundProtocol::set_round_observer).
  std::function<void(const ProtocolSnapshot&)> on_round;
  /// Continue from this snapshot (a coordinated rollback) instead of starting from the
  /// initial poses; every other agent must resume from its snapshot of the same round.
  const ProtocolSnapshot* resume_from = nullptr;
  /// Called with the name of a phase after which the agent's memory is worth a line
  /// (runtime/phase_memory.hpp): "block layout", "block set-up", "round K" at K = 1, 2, 5,
  /// 10, 20, 50, ... of the solve, "rounds". Empty: not called.
  std::function<void(const std::string&)> on_phase;
  /// Called once the block's problem and preconditioners are built, before the first round:
  /// the set-up's temporaries are freed then (the agent hands that heap back to the kernel).
  std::function<void()> after_set_up;
  /// Called on every agent at each progress point of a stage after the rounds: a message
  /// handled in the Newton refinement or the certificate, an iteration of the rounding's
  /// translation CG (where agent 0 reports progress). Empty: not called.
  std::function<void(ProgressStage)> on_progress_point;
};

/// Core's solver options for `options` (core's defaults where a field is 0 or empty).
DistributedOptions distributed_options_of(const RunOptions& options);

/// Runs this agent's part of the distributed solve. `receive_timeout_s` bounds every wait
/// for a peer's message (a throw names the missing sender). RollbackRequested from the
/// channel propagates: the caller calls again with the snapshot of that round.
RoundLoopResult run_round_loop(const AgentLocalData& local, ProtocolChannel& channel,
                               double receive_timeout_s, const RoundLoopHooks& hooks = {});

}  // namespace tessera::agent
