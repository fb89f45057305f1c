#pragma once
// Distributed PGO over a partition: N agents (one per block) run RBCD, RBCD++ or IRBCD through
// the round protocol, here in one process (in_process_driver.hpp). Options in, result out.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <tessera/distributed/block_selection.hpp>
#include <tessera/distributed/distributed_initialization.hpp>
#include <tessera/distributed/in_process_driver.hpp>
#include <tessera/distributed/irbcd.hpp>
#include <tessera/distributed/local_rounds.hpp>
#include <tessera/distributed/newton_refine_options.hpp>
#include <tessera/distributed/newton_refine_result.hpp>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/distributed/rbcd_plus_plus.hpp>
#include <tessera/distributed/stage_records.hpp>
#include <tessera/distributed/staircase_options.hpp>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

enum class DistributedAlgorithm { kRbcd, kRbcdPlusPlus, kIrbcd };

/// "rbcd", "rbcd++", "irbcd".
const char* algorithm_name(DistributedAlgorithm a);
/// Throws InputError listing the valid names.
DistributedAlgorithm parse_algorithm(const std::string& name);

struct DistributedOptions {
  DistributedAlgorithm algorithm = DistributedAlgorithm::kIrbcd;
  int rank = 5;  ///< Relaxation rank r >= d (5: the reference optima's rank).
  DistributedInit initialization = DistributedInit::kChordal;
  int robots = 0;  ///< Robots of the distributed initialization; 0 = number of blocks.
  SelectionRule selection = SelectionRule::kGreedy;
  /// Update a whole colour class of blocks per round (an independent set of the block
  /// adjacency graph: those agents compute at the same time), the default since it needs fewer
  /// rounds and less time on every benchmark graph (docs/irbcd.md section 4); false = one block
  /// per round, as RBCD and the public baseline count rounds.
  bool parallel = true;
  std::uint64_t seed = 1;       ///< Shared by all agents (uniform selection).
  double grad_norm_tol = 0.01;  ///< Stop when ||grad f|| (full cost) <= this; >= 0.
  int max_rounds = 10000;       ///< >= 0.
  /// Stop when a round decreases f by less than this fraction of f (0 = off: with one block
  /// per round a tiny decrease says little about the others).
  double rel_cost_decrease_tol = 0.0;
  BlockUpdateOptions block_update;
  /// IRBCD's block minimisation where it differs from `block_update` (RBCD and RBCD++ always
  /// use block_update): the most trust-region steps of an update (>= 0; 0 = block_update's
  /// trust_region_steps) and the block-gradient reduction that ends it early (< 1; negative =
  /// block_update's grad_reduction). Default: a second step only when the first left the
  /// block's gradient above 0.2 of its start value (the paper's "minimise the block" done a
  /// little more exactly where one step is not enough): IRBCD then beats RBCD++ on 27 of 30
  /// paper-graph cells instead of 25 at the same CPU per round; RBCD++ gains nothing from it and
  /// keeps one step (docs/irbcd.md section 5).
  int irbcd_trust_region_steps = 2;
  double irbcd_grad_reduction = 0.2;
  RbcdPlusPlusOptions rbcd_plus_plus;
  IrbcdOptions irbcd;
  /// Two-level rounds: a rigid correction of every block per scheduled round
  /// (coarse_correction.hpp; docs/irbcd.md, "Coarse correction").
  CoarseOptions coarse;
  /// Local rounds: only blocks whose gradient is above a bound update, take momentum steps
  /// and send (local_rounds.hpp). Off for batch solves (every block starts far from its
  /// optimum there); the online runs turn it on. Not with `coarse`.
  LocalRoundOptions local_rounds;
  /// After the solve, certify global optimality distributedly and climb the staircase
  /// (docs/distributed-certification.md). Off by default for `tessera solve`.
  bool certify = false;
  StaircaseOptions staircase;
  /// After each solve stage that converged, Newton steps on the whole problem to
  /// refine.grad_norm_tol (newton_refine_options.hpp; by default only where the rounds' trace says
  /// they stopped short of their limit, `--refine auto`).
  NewtonRefineOptions refine;
  /// Round the final iterate to SE(d) (`poses`, `cost`). Off for callers that keep the lifted
  /// iterate and whose graph may not be connected yet (the online engine's steps), where the
  /// translation solve of the rounding has no unique answer.
  bool round_result = true;
  DeliveryOrder delivery = DeliveryOrder::kFifo;  ///< In-process delivery order (tests).
  std::uint64_t delivery_seed = 1;
  /// In process: the agents handle their messages on this many threads (with kFifo; the same
  /// iterates as 1, see in_process_driver.hpp). 1..64.
  int threads = 1;

  /// Throws InputError naming the first invalid field.
  void validate() const;
  /// The block update options of `algorithm`: block_update with the IRBCD overrides applied
  /// when the algorithm is IRBCD.
  BlockUpdateOptions algorithm_block_update() const;
};

struct DistributedRound {
  int round = 0;           ///< Counted over every solve stage of the staircase.
  int rank = 0;            ///< Rank of the solve stage.
  double cost = 0.0;       ///< f(Y^k) of the lifted iterate, full sum.
  double grad_norm = 0.0;  ///< ||grad f(Y^k)||.
  std::vector<int> selected;
  bool restart = false;
  std::uint64_t bytes = 0;  ///< Bytes of the messages tagged with this round.
  double elapsed_s = 0.0;
};

struct DistributedResult {
  int agents = 0;
  int rounds = 0;  ///< Block-update rounds done, all solve stages (restarts' redos inside).
  /// Solve stages run (one per rank solved or refined): each opens with a pose exchange and
  /// ends with a status round, two message steps beyond two a round.
  int solve_stages = 0;
  int restarts = 0;
  /// grad_norm, max_rounds, relative_decrease or stalled (the iterate stopped moving above
  /// the tolerance: RoundProtocol::stop_reason()).
  std::string stop_reason;
  std::vector<DistributedRound> trace;
  std::uint64_t bytes_exchanged = 0;  ///< Every message (solve, certificate, escape).
  std::uint64_t messages = 0;
  /// The longest chain of messages (DeliveryStats::longest_chain): the message steps waited
  /// through one after another, certificates and escapes included.
  std::uint64_t longest_chain = 0;
  // Certification (options.certify): nullopt / zero when off.
  std::optional<bool> certified;
  double min_eigenvalue = 0.0;         ///< Last certificate's smallest Ritz value of S.
  double certificate_tolerance = 0.0;  ///< Its eta.
  double certificate_residual = 0.0;   ///< Its Ritz residual.
  /// Its weak-duality bound (dual_bound.hpp): NaN lower bound when not proved.
  DualBound certificate_bound;
  int certificate_rounds = 0;  ///< LOBPCG iterations, all certificates.
  std::uint64_t certificate_bytes = 0;
  /// Solver rounds (included in `rounds`) spent refining ranks whose certificate at the
  /// solver's tolerance was inconclusive (StaircaseOptions::grad_norm_tol).
  int refine_rounds = 0;
  /// The Newton refinements (DistributedOptions::refine), one per refined solve stage.
  std::vector<NewtonRefineResult> refines;
  int escape_rounds = 0;  ///< Line-search trials, all escapes.
  std::uint64_t escape_bytes = 0;
  int final_rank = 0;
  std::vector<CertifyStageRecord> certificates;
  std::vector<EscapeStageRecord> escapes;
  /// Block updates of all agents (restarts' redos included), their truncated-CG iterations,
  /// the updates preconditioned with the tangent factor, and that factor's factorizations.
  long long block_updates = 0;
  long long tcg_iterations = 0;
  long long tangent_updates = 0;
  long long tangent_factorizations = 0;
  Eigen::MatrixXd X;             ///< Final lifted iterate (r x (d+1)n, global order).
  double relaxation_cost = 0.0;  ///< f(X).
  double grad_norm = 0.0;        ///< ||grad f(X)||.
  std::vector<Pose> poses;       ///< X rounded to SE(d).
  double cost = 0.0;             ///< Objective of `poses` (reference convention).
  /// Seconds: initial guess + agents' set-up (block problems, preconditioners), the rounds,
  /// the final rounding (rotations and the translation solve), the whole call.
  double init_s = 0.0, solve_s = 0.0, rounding_s = 0.0, wall_s = 0.0;
  /// Process CPU time of the rounds (all agents, in one process): unlike solve_s it does not
  /// grow when other jobs share the machine.
  double solve_cpu_s = 0.0;
  /// Estimated compute time of the same rounds with each agent on its own machine: per
  /// message (stage, round), the slowest agent's CPU time, summed (DeliveryStats). With
  /// `parallel` several agents compute in one round; this is the time that then matters.
  double critical_path_cpu_s = 0.0;

  /// A readable report of the run (agents, rounds and stop, cost, certificate, staircase,
  /// traffic, timing), like CentralizedResult::full_report(); distributed_report.cpp.
  std::string full_report() const;
};

/// Every wait for peers of a run but its certification's (certificates, escapes; docs/robust.md,
/// "JSON and files": message_steps_total): two a round (docs/irbcd.md), two a solve stage (its
/// opening pose exchange and closing status round) and the Newton refinements' message steps. Equal
/// to longest_chain without certification. A robust run counts more: message_steps of its
/// GncDistributedResult (robust/gnc_distributed.hpp).
long long message_steps(const DistributedResult& r);

/// Solves `graph` with the blocks of `assignment` (block id per pose, 0..N-1, none empty).
/// `initial`: initial poses; empty = options.initialization.
DistributedResult solve_distributed(const PoseGraph& graph, const std::vector<int>& assignment,
                                    const DistributedOptions& options,
                                    const std::vector<Pose>& initial = {});

/// The same from a lifted starting point X0 (r x (d+1)n, global pose order, each block [Y_i |
/// p_i] with Y_i in St(d, r)): e.g. the iterate of an earlier run whose agents changed, so a run
/// continues where it was instead of starting over. Throws InputError when X0 has the wrong
/// shape. `known_grad_norm`: ||grad f(X0)|| as a finished solve of the same problem summed
/// it (NaN: not known); where it settles the rounds at their first status, the agents start at
/// their Newton refinement with X0's neighbour poses (CertifiedAgent::set_known_start), without
/// the rounds' opening pose exchange and round-0 status.
DistributedResult solve_distributed_from_lifted(
    const PoseGraph& graph, const std::vector<int>& assignment, const DistributedOptions& options,
    const Eigen::MatrixXd& X0, double known_grad_norm = std::numeric_limits<double>::quiet_NaN());

class AgentState;
/// The same with agents whose states already exist (states[b] = block b of `layout`, built
/// over `graph`'s measurements, each at its starting point): an online run keeps them from
/// step to step and grows them in place (live_blocks.hpp) instead of building every block
/// problem and preconditioner again. The states hold the final iterate afterwards.
/// `known_grad_norm` as above (the states' neighbour copies must then be current).
DistributedResult solve_distributed_with_states(
    const PoseGraph& graph, const BlockLayout& layout, const std::vector<AgentState*>& states,
    const DistributedOptions& options,
    double known_grad_norm = std::numeric_limits<double>::quiet_NaN());

}  // namespace tessera
