#pragma once
// The online run in one process: stream batches arrive while the agents solve; at each step
// (a round boundary) the engine absorbs what was received (in one process every agent holds
// the same batches; over DDS absorb_gate.hpp decides what all of them hold), extends the estimate
// to the new poses by composition (estimate_extension.hpp), and runs the agents' round protocol
// (in_process_driver.hpp) from the current iterate until the gradient is back under the tolerance.
// The blocks follow the robots: one agent per robot seen so far, so a robot that starts late gets
// its agent when its first pose arrives. A step with nothing new and the gradient under the
// tolerance does no round and exchanges no message (the agents idle). The momentum of the
// accelerated methods restarts at every change of the problem: it carries curvature information of
// the old objective, which a new measurement makes wrong. At the end a certificate is run
// (DistributedOptions::certify's staircase) from the last iterate.

#include <Eigen/Core>
#include <chrono>
#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/online/component_alignment.hpp>
#include <tessera/online/graph_stream.hpp>
#include <tessera/online/live_blocks.hpp>
#include <tessera/online/step_points.hpp>
#include <tessera/online/stream_batch.hpp>
#include <vector>

namespace tessera {

/// The agents' solver of an online run: DistributedOptions' defaults with local rounds on
/// (after a batch, most blocks are converged and only those near the new data need work) and
/// the batch refinement off (the steps' Newton steps are OnlineOptions::newton_steps).
DistributedOptions online_solver_options();

struct OnlineOptions {
  /// The agents' solver (algorithm, rank, tolerance, selection, local rounds, ...). Its
  /// `certify` and `initialization` are not used: poses are initialised by composition, and
  /// certification is `certify_at_end`.
  DistributedOptions solver = online_solver_options();
  /// Run the distributed certificate (with the staircase of solver.staircase) after the
  /// last batch.
  bool certify_at_end = true;
  /// The partition follows the graph: blocks start as the robots, new poses join the block of
  /// most of their measurements, and border poses move out of over-full blocks and, when the
  /// cut passes rebalance.cut_fraction, to cut fewer measurements (block_rebalance.hpp) after
  /// each absorbed step.
  RebalanceOptions rebalance;
  /// run_online only. false: one step per distinct batch stamp (deterministic). true: the
  /// stamps are a real-time clock; a step absorbs every batch published by the time the
  /// previous step ended (its measured wall time), as a live run would.
  bool real_time = false;
  /// run_online only, > 0: a step every this many seconds of stream time, absorbing every batch
  /// published by then (a back end that steps at a fixed period: the same steps whatever the
  /// machine's load, so a step's CPU time against this period says whether the agents keep
  /// up). 0 = off. Not with real_time. >= 0.
  double step_every_s = 0.0;
  /// run_online only: > 0 runs the distributed certificate every this many seconds of
  /// stream time (at the first step after each period), on the graph received so far, robots
  /// that have not met included (OnlineEngine::certify); 0 = only at the end. >= 0.
  double certify_every_s = 0.0;
  /// A block that grows keeps its tangent preconditioner factor (its new poses appended to it,
  /// TangentPreconditioner::grow) until it holds this fraction more poses than the factor was
  /// computed for (live_blocks.hpp); a block that only gets new measurements keeps its factor
  /// (stale, still positive definite). 0 = a new factor at every step that brought the block new
  /// poses: the default, because the appended solves cost more than the factorizations they
  /// save (callgrind, a generated 1,000-pose grid, 5 robots, a step every 0.1 s: 3.30 G
  /// instructions at 0, 3.79 G at 0.1, 6.38 G at 0.25; docs/online.md). >= 0.
  double refactor_growth = 0.0;
  /// With newton_steps: a block that grows keeps its factor, its new poses appended to it
  /// (TangentPreconditioner::grow), for the step's first Newton step only; each such block
  /// builds its new factor at the first accepted Newton step's point
  /// (NewtonRefineOptions::refactor_grown_factors), so the step's later CGs are preconditioned
  /// as with refactor_growth 0. Why: that first point is the step's first estimate near the new
  /// optimum (the gap latency, docs/online.md), and the grown blocks' new factors were most of
  /// the CPU before it. Overrides refactor_growth while on. Default false: on the 50,000-pose
  /// grid (3,500-pose 3-D blocks) appending the new poses costs more than the factorizations it
  /// defers (the first point 2.9-3.2 against 1.7-1.8 CPU-s after the same 4 CG iterations),
  /// though the factors built at the first point cut the run's CG iterations by a fifth
  /// (docs/online.md, "The first Newton step on grown factors").
  bool first_step_on_grown_factors = false;
  /// How a step brings ||grad f|| back under solver.grad_norm_tol after new data. true: block-
  /// coordinate rounds down to max(newton_after_grad_tol, the tolerance), then distributed
  /// trust-region Newton steps (newton_refine.hpp, solver.refine's settings with its tolerance
  /// set to the solver's, its relative-decrease stop off and the block factors kept across its
  /// steps) from there; Newton steps that stop above the tolerance (a cap, or a stalled trust
  /// region) are followed by rounds from where they stopped, in the same step (in process; over
  /// DDS the next epoch solves again). false: rounds only. Why: a new loop closure bends whole
  /// chains, a smooth error the rounds remove slowly, while the Newton steps' CG works on all
  /// blocks at once (a generated 1,000-pose city, 5 robots, a step every 0.1 s of stream: ~290
  /// rounds a step against 4-7 Newton steps and ~100 CG iterations; docs/online.md, "Newton
  /// steps").
  bool newton_steps = true;
  /// See newton_steps: +infinity (the default) starts the Newton steps from the warm start,
  /// with no round. > 0.
  double newton_after_grad_tol = std::numeric_limits<double>::infinity();
  /// The Newton steps' CG stop (NewtonRefineOptions::forcing): a step's CG ends at
  /// ||r|| <= newton_forcing ||g|| while ||g|| >= newton_forcing (then the superlinear
  /// ||g||^2). Tighter than the batch refinement's 0.1 because an online step starts close to
  /// the quadratic region (new_pose_placement.hpp) and the tolerance is far below the start
  /// (|grad f| ~1e3 -> 1e-3): at 0.1 each Newton step gained one decade. Generated 1,000-pose
  /// city / grid3d / sphere, 5 robots, a step every 0.1 s: Newton steps 108 / 97 / 77 at 0.1,
  /// 75 / 76 / 64 at 0.03; CG iterations 1,747 / 632 / 575 against 1,646 / 601 / 529. In (0, 1).
  double newton_forcing = 0.03;
  /// The Newton steps' coarse correction (NewtonRefineOptions::coarse): kNone (block Jacobi,
  /// the default), kBlocks (plus one rigid motion per block) or kSmoothed (plus the rigid
  /// motions of newton_coarse_aggregates smoothed pieces of each block, the space built
  /// from the linked graph at every solve). Only blocks in a group of newton_coarse_min_blocks
  /// linked blocks or more take part: a robot that has met no other is left out (its motions are a
  /// gauge, its inner bending block Jacobi's work), so before the robots meet the steps are block
  /// Jacobi's (tangent_coarse_space.hpp). Once they meet, the error a closure leaves is bending
  /// across blocks, which block Jacobi moves one block boundary per CG iteration: a generated
  /// 20,000-pose grid over 10 robots, a step every 0.1 s, first 11,010 poses: 12,442 CG
  /// iterations without, 6,161 with kBlocks, 4,071 with kSmoothed and newton_coarse_min_blocks = 2
  /// (at 10,000-11,000 poses 527 / 103 / 36 a step; CPU 140 / 105 / 100 s, load 6-19). Off by
  /// default: while robots have only met in pairs kSmoothed cuts fewer iterations than it costs
  /// (the same grid at 4,600-8,000 poses: 48 against 67 CG iterations a step, 0.96 against 0.55
  /// CPU-s); and the coarse matrix is summed at every accepted Newton step (docs/online.md, "The
  /// coarse correction").
  NewtonRefineOptions::Coarse newton_coarse = NewtonRefineOptions::Coarse::kNone;
  /// With newton_coarse: the linked blocks a group needs for the correction to apply to it
  /// (NewtonRefineOptions::coarse_min_blocks); smaller groups, robots met in pairs for
  /// instance, take block Jacobi's steps. Default 3: a pair's relative motion saves few CG
  /// iterations for the coarse sums and products it costs. The 20,000-pose grid above with
  /// kSmoothed, first 11,010 poses: at 4,600-8,000 poses (pairs only) 67.2 CG iterations and
  /// 0.54 CPU-s a step with 3 (block Jacobi's counts exactly) against 48.4 and 0.91 with 2; in
  /// all 5,249 against 4,071 CG iterations, 481 against 494 Newton steps, 67 against 93 CPU-s
  /// (load 6-16; docs/online.md, "The coarse correction"). >= 2.
  int newton_coarse_min_blocks = 3;
  /// With kSmoothed: the pieces of each block (NewtonRefineOptions::coarse_aggregates), or
  /// kCoarseAggregatesAuto: one piece per kCoarseAutoPosesPerPiece poses of the block, rounded,
  /// 1..kCoarseAutoMaxPieces, chosen again at every solve as the blocks grow. Default 8: auto
  /// saves a tenth of the instructions on sphere2500 (500-pose blocks, whose 8 pieces make the
  /// coarse matrix's dense products cost more than the blocks' own) but costs more than 8 on
  /// the grid and city10000 while their blocks are small (city10000's 2D chains want many
  /// pieces at any block size; docs/online.md, "Pieces per block"). >= 0 (0 = auto).
  int newton_coarse_aggregates = 8;
  static constexpr int kCoarseAggregatesAuto = 0;
  static constexpr int kCoarseAutoPosesPerPiece = 250;
  static constexpr int kCoarseAutoMaxPieces = 8;
  /// New poses that new loop closures tie to the estimate are placed by least squares against
  /// every new measurement after composition (new_pose_placement.hpp), not only along their
  /// odometry. false: composition only.
  bool place_new_poses = true;
  /// When a measurement first links two pieces of the graph (robots that meet, a robot's first
  /// poses started from its front end's guess), move the smaller piece rigidly so that the
  /// measurement has zero residual (component_alignment.hpp): for front ends whose frames are
  /// unrelated. Off by default: where the guesses share one frame up to drift (the generated
  /// graphs: odometry composed from pose 0 across robots) one link is a worse anchor than that
  /// frame (a generated 20,000-pose grid over 10 robots, a step every 20 s: 8,540 CG iterations
  /// against 3,808 without; the same final cost). docs/online.md, "Pieces that meet".
  bool align_merged_pieces = false;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// The agents' solver for a step that absorbed new data (OnlineOptions::newton_steps): the
/// in-process engine's and `tessera-agent --online`'s, so both take the same steps.
DistributedOptions online_step_solver(const OnlineOptions& options);

/// With `solver`'s Newton steps and their smoothed coarse correction
/// (NewtonRefineOptions::Coarse::kSmoothed): gives every state `blocks` holds the smoothed
/// pieces of its linked graph and blocks. Those change at every step, so the pieces are built
/// again for every solve (a pass over the measurements); every DDS agent builds the same ones
/// from the same graph. Otherwise does nothing.
void use_online_refine_space(const LiveBlocks& blocks, const DistributedOptions& solver);

/// How much a growing block's factor may grow before the block builds a new one
/// (LiveBlocks' refactor_growth): options.refactor_growth, or unbounded with
/// first_step_on_grown_factors and newton_steps (the Newton steps build it after their first
/// step). The in-process engine's and `tessera-agent --online`'s, so both keep the same factors.
double live_refactor_growth(const OnlineOptions& options);

/// One step of the online run (the JSON `updates` array of `tessera launch --online`).
struct OnlineUpdate {
  double time_s = 0.0;           ///< When the step began (stream clock).
  std::size_t batches = 0;       ///< Batches absorbed.
  std::size_t poses = 0;         ///< New poses.
  std::size_t measurements = 0;  ///< New measurements.
  std::size_t total_poses = 0;   ///< Graph size after the step.
  std::size_t total_measurements = 0;
  int agents = 0;                  ///< Blocks (robots) during the step.
  std::size_t moved = 0;           ///< Poses that changed block (rebalance) before the rounds.
  std::size_t largest_block = 0;   ///< Largest block's poses during the rounds.
  std::size_t smallest_block = 0;  ///< Smallest block's poses during the rounds.
  /// Measurements between two blocks during the rounds (0 when the cut refinement is off,
  /// RebalanceOptions::cut_fraction = 1).
  std::size_t cut = 0;
  int rounds = 0;      ///< Rounds until the gradient was back under tolerance.
  double ms = 0.0;     ///< Wall time of the step (absorb, extend, rounds).
  double cpu_s = 0.0;  ///< Process CPU time of the step.
  /// Of the step's wall time: the agents' set-up (block problems, preconditioner factors),
  /// and the process CPU of the rounds alone.
  double setup_s = 0.0;
  double rounds_cpu_s = 0.0;
  /// The rounds' compute time with each agent on its own machine: per message step, the
  /// slowest agent's CPU time, summed (DistributedResult::critical_path_cpu_s).
  double critical_path_cpu_s = 0.0;
  /// Publication of the oldest absorbed batch to the end of the step (stream clock; with
  /// real_time the step's wall time counts as stream time).
  double latency_s = 0.0;
  /// latency_s with the step's process CPU time (cpu_s) in place of its wall time: what the
  /// latency would be with this process alone on one core, so it does not grow with the
  /// machine's load as latency_s does. Its load-free companions are the step's message steps
  /// (rounds + newton_message_steps) and CG iterations.
  double latency_cpu_s = 0.0;
  /// Publication of the newest absorbed batch (stream clock): the graph of this step is
  /// complete from then on, so time_s minus it is how long its last data waited for the step.
  double newest_publication_s = 0.0;
  std::uint64_t bytes = 0;  ///< Protocol bytes of the step's rounds.
  double grad_norm = 0.0;   ///< ||grad f|| at the end of the step.
  /// Why the rounds stopped: grad_norm, or stalled (the iterate stopped moving just above the
  /// tolerance; the next data restarts it), or max_rounds; unchanged when no round ran because
  /// every new measurement only placed a new pose (zero residual: the gradient of the converged
  /// iterate did not change).
  std::string stop_reason;
  double relaxation_cost = 0.0;  ///< f(Y) at the end of the step.
  /// OnlineOptions::newton_steps: the step's Newton steps (accepted or not), their CG
  /// iterations, and message steps (neighbour exchanges plus all-agent sums; a round is one).
  int newton_steps = 0;
  int newton_cg_iterations = 0;
  int newton_message_steps = 0;
  /// The blocks' tangent preconditioner factorizations in this step (set-up and Newton steps)
  /// and their floating-point operations as CHOLMOD's symbolic analysis predicts them: the
  /// preconditioner's cost, free of the machine's load.
  long long factorizations = 0;
  double factor_flops = 0.0;
  /// Block states built from scratch in this step's set-up (LiveBlocks::sync: new blocks, and
  /// the blocks a re-partition gave or took poses); the others grew in place or were kept.
  long long blocks_built = 0;
  /// OnlineOptions::align_merged_pieces: measurements that linked two pieces of the graph at
  /// this step, and the poses moved to align them.
  std::size_t merges = 0;
  std::size_t merge_poses_moved = 0;
};

/// A certificate taken while the graph was growing (OnlineOptions::certify_every_s).
struct OnlineCertificate {
  double time_s = 0.0;
  std::size_t poses = 0;
  bool certified = false;
  double min_eigenvalue = 0.0;
  double cpu_s = 0.0;
  /// The certificate failed and the staircase's climb found a certified optimum at a higher
  /// rank: the iterate was brought back to the run's rank from there (project_to_rank).
  bool escaped = false;
  double cost_before = 0.0, cost_after = 0.0;  ///< f(Y) before the certificate and after it.
};

struct OnlineResult {
  std::vector<OnlineUpdate> updates;
  /// For every absorbed batch: its publication to the end of the step that absorbed it
  /// (stream clock), in absorption order. Steps that take long absorb many batches, so this,
  /// not the per-step latency_s, is what a robot waiting for its estimate sees.
  std::vector<double> batch_latency_s;
  /// The same with the step's process CPU time in place of its wall time
  /// (OnlineUpdate::latency_cpu_s).
  std::vector<double> batch_latency_cpu_s;
  std::vector<OnlineCertificate> certificates;  ///< Taken during the run (certify_every_s).
  int rounds = 0;               ///< All steps' rounds (the final certificate's excluded).
  int repartitions = 0;         ///< Steps that moved poses between blocks.
  std::size_t poses_moved = 0;  ///< Poses moved over all steps.
  std::uint64_t bytes = 0;
  double cpu_s = 0.0;  ///< All steps' process CPU time.
  // The final solve from the last iterate, with the certificate when certify_at_end.
  std::optional<bool> certified;
  double min_eigenvalue = 0.0;
  int final_rounds = 0;  ///< Rounds of that final solve (0 when already converged).
  double cost = 0.0;     ///< Objective of `poses` (reference convention).
  double grad_norm = 0.0;
  std::vector<Pose> poses;    ///< Final estimate, by stream id (graph order).
  PoseGraph graph;            ///< The graph received (stream ids).
  std::vector<PoseKey> keys;  ///< Stream key of each id.
};

class OnlineEngine {
 public:
  /// `d`: the stream's dimension (2 or 3). Throws InputError for bad options.
  OnlineEngine(int d, const OnlineOptions& options);

  /// A batch arrives (buffered: it enters the problem at the next step).
  void receive(const StreamBatch& batch);
  /// A round boundary: absorbs the received batches and solves until the gradient is under
  /// the tolerance; idle (no round, no message) when nothing is new and it already is.
  OnlineUpdate step(double now_s = 0.0);
  /// Certifies the current iterate on the graph received so far (the distributed certificate
  /// after the rounds). When it fails, the staircase climbs from the critical point; a climb
  /// that ends certified at a higher rank is brought back to rank r (project_to_rank: exact when
  /// that optimum has rank <= r, as on exact relaxations) and the run goes on from there, so a
  /// spurious critical point found while streaming is left at once, not at the end. Pieces of
  /// the graph that have not met are certified together (the certificate matrix is block
  /// diagonal over them: it needs no common frame, unlike rounding). nullopt before the first
  /// solve.
  std::optional<OnlineCertificate> certify(double now_s);
  /// Solves from the current iterate (certifying when asked) and returns the run's figures.
  OnlineResult finish();

  const GraphStream& stream() const { return stream_; }
  /// Current lifted iterate (r x (d+1)n, stream ids); empty before the first pose.
  const Eigen::MatrixXd& iterate() const { return X_; }
  /// Current estimate rounded to SE(d), by stream id; empty while the graph received is not
  /// connected (robots that have not met yet share no frame).
  std::vector<Pose> estimate() const;
  /// Block (agent) of each stream id: its robot's position in stream().robots() unless the
  /// rebalance moved it.
  const std::vector<int>& assignment() const { return owner_; }
  /// Whether the next steps record the estimates they pass through (step_points()): off by
  /// default, and meant for a few steps only (each point is a copy of the lifted iterate).
  void keep_step_points(bool keep) { keep_points_ = keep; }
  /// The last step's points (step_points.hpp) when it kept them, in time order: absorbed, each
  /// accepted Newton step's, end; empty otherwise. Cleared when the next step begins.
  const std::vector<StepPoint>& step_points() const { return points_; }

 private:
  /// Runs the agents from X_ on the poses some measurement touches and writes their result
  /// back into X_ (when the rank did not change: a staircase climb leaves X_ as it was).
  /// `keep_newton_points`: appends each accepted Newton step's point to points_.
  DistributedResult solve_linked(const DistributedOptions& solver, bool keep_newton_points = false);
  /// The step's clocks since it began (wall, process CPU).
  double step_wall_s() const;
  double step_cpu_s() const;
  /// A step's solver with rounds only (after Newton steps that stopped above the tolerance).
  DistributedOptions plain_step_solver() const;

  OnlineOptions options_;
  GraphStream stream_;
  std::unique_ptr<LiveBlocks> blocks_;     // the agents' states, kept from step to step
  ComponentAlignment pieces_;              // the graph's pieces, aligned when they meet
  std::size_t extended_measurements_ = 0;  // measurements the iterate was extended over
  std::vector<StreamBatch> received_;
  Eigen::MatrixXd X_;
  std::vector<int> owner_;                                    // block of each stream id
  bool converged_ = true;                                     // gradient under tolerance at X_
  double last_grad_norm_ = 0.0, last_relaxation_cost_ = 0.0;  // at the end of the last solve
  OnlineResult totals_;
  bool keep_points_ = false;
  std::vector<StepPoint> points_;                          // the last step's, when kept
  std::chrono::steady_clock::time_point step_wall_start_;  // the running step's start
  double step_cpu_start_ = 0.0;
  TangentFactorTotals step_factors_before_;  // the blocks' at the running step's start
};

/// Called after every step of run_online that did work (not for idle steps).
using OnlineObserver = std::function<void(const OnlineEngine&, const OnlineUpdate&)>;
/// Called before every step of run_online with the batches it is about to absorb (received,
/// not yet in the graph): e.g. to have the engine keep that step's points (keep_step_points).
using OnlineStepStart = std::function<void(OnlineEngine&, std::size_t batches)>;

/// Plays `batches` (ordered by stamp) into an engine (see OnlineOptions::real_time) and
/// finishes it.
OnlineResult run_online(int d, const std::vector<StreamBatch>& batches,
                        const OnlineOptions& options, const OnlineObserver& observer = {},
                        const OnlineStepStart& before_step = {});

}  // namespace tessera
