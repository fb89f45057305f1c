#pragma once
// Distributed second-order refinement of a lifted iterate: Riemannian trust-region Newton steps
// on the WHOLE lifted problem, run by the agents together after the block-coordinate rounds.
//
// Why: block-coordinate descent reaches a gradient of 1e-2 in tens of rounds, but on long chains
// (parking-garage, ais2klinik) its slow modes leave the iterate 1e-4 relative above the optimum,
// and each further decade costs hundreds of rounds (docs/benchmarks/launch_phases.md). A Newton
// step solves for all modes at once; its truncated conjugate gradient (CG) needs only what the
// agents already exchange:
//   * Hessian-vector product: each agent forms its own block's rows of Hess f(X)[v] from its own
//     entries of v and its neighbours' public entries (one neighbour exchange per product);
//   * CG's inner products are all-agent sums in agent-id order (bit-identical on every agent);
//   * the preconditioner, where the team's interface is small (options.interface_max_coordinates),
//     is the Hessian's inverse by substructuring (distributed/interface_solve.hpp: each block's
//     factor and the interface's Schur complement, which agent 0 factors once per point and solves
//     with for every agent, NewtonRefineOptions::SigmaFactoring::kShipSolves), so a Newton step's
//     CG takes 1-3 iterations; elsewhere block Jacobi (AgentState::precondition: the tangent factor
//     of its block, else its Q_BB factor), optionally with a coarse correction over rigid motions
//     of smoothed pieces of the blocks (options.coarse, distributed/tangent_coarse_space.hpp):
//     block Jacobi alone moves information one block boundary per CG iteration.
// CG is in the Chronopoulos-Gear form (the two inner products of an iteration from one
// reduction, <p, Hp> by recurrence), so an iteration is one exchange then one reduction.
// The trust region (Steihaug-Toint truncated CG in the preconditioner's norm, ratio test on the
// true cost) keeps a step that leaves the quadratic model's region from raising the cost: the
// trial point's public poses are exchanged and its cost and gradient summed (one exchange and
// one reduction per step); an accepted trial is the next point with no further message. A
// rejected trial is retried along the same CG step at a quarter of its length (no new CG) before
// the region shrinks. The Hessian product is projected onto the tangent space (CG's residual must
// be tangent: the tangent preconditioner maps a normal part to zero). Trial points move each pose
// by the SE(d) exponential of its own twist (distributed/rigid_retraction.hpp): a Newton step on
// a long chain turns whole parts of the map, which the polar retraction with additive
// translations stretches (ais2klinik: f rose by 178 where the model predicted -0.047).
// One agent's state machine (messages in -> messages out, no transport), driven like
// RoundProtocol and CertificateProtocol, so in-process and DDS runs take identical iterates.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/problem/block_problem.hpp>
#include <utility>
#include <vector>

namespace tessera {

class TangentCoarseSpace;
class InterfaceSolve;
class InterfaceAnalysisStore;
class PipelinedCg;
class CoarseHessianColumns;
class TranslationPreconditioner;
class TranslationInterfaceSolve;
class GaugeSpace;

struct NewtonRefineOptions {
  /// Run the refinement after the block-coordinate solve reached its own tolerance (a solve
  /// that ran out of rounds is not refined). On by default, with `when` = kIfRoundsSlow
  /// (`--refine auto`, the default of `tessera solve`'s distributed algorithms, the coordinator
  /// and `launch` alike, so in-process and DDS runs take the same steps); `--refine none`
  /// switches it off. Code that sets it on for a refinement after every solve sets `when` too.
  bool enabled = true;
  /// When an enabled refinement runs. kAlways (`--refine newton`): after every solve stage that
  /// converged. kIfRoundsSlow (`--refine auto`): only where the rounds' own trace says they
  /// stopped more than auto_gap_tol of f above their limit (distributed/rounds_tail.hpp: the
  /// cost decrease of the last auto_window rounds against the window before, as a geometric
  /// tail with its rate capped at 0.9). Why: at gradient 0.01 the rounds end within 3.4e-7 of
  /// f* on most paper graphs, where a refinement costs a Newton step of 23-46 CG iterations
  /// for nothing, and 1e-4 above on long chains, where it is the cheap way to 1e-6
  /// (docs/newton-refine.md, "Reaching 1e-6 by default"). Identical on every agent (the
  /// trace's costs are all-agent sums).
  enum class When { kAlways, kIfRoundsSlow };
  When when = When::kIfRoundsSlow;
  /// kIfRoundsSlow: refine when the estimated relative gap is above this. > 0. The estimate
  /// was above the true gap on the paper graphs (parking-garage aside, 1.5-4x; there it is
  /// 3.8e-4 against 6.8e-4), so 1e-7 leaves a margin of ten to launch's goal of 1e-6.
  double auto_gap_tol = 1e-7;
  /// kIfRoundsSlow: rounds per window of the estimate. >= 1.
  int auto_window = 5;
  /// Stop when ||grad f|| <= this (absolute, as the solver's grad_norm_tol). > 0.
  double grad_norm_tol = 1e-6;
  /// Stop after an accepted step that lowered f by at most this fraction of f. A full Newton
  /// step's decrease is about the gap it closes (parking-garage: predicted 9.0e-4, 3.3e-6,
  /// 3.1e-7 at gaps of 9.0e-4, 3.6e-6, 3.1e-7 before the step), but where the trust region
  /// limits the steps (ais2klinik) a step lowers f by less than the gap left: there 1e-5 stopped
  /// at a relative gap of 3.9e-5, 1e-7 at 1.4e-9. Only at a gradient norm at or below the
  /// start's: a step cut short by the trust region lowers f little too. >= 0; 0 = off.
  double relative_decrease_tol = 1e-7;
  /// Most trust-region steps (accepted or not). > 0. (ais2klinik from the rounds' 0.01: 33.)
  int max_steps = 100;
  /// Most CG iterations over all steps (each one exchange and one reduction). > 0.
  /// (ais2klinik from the rounds' 0.01: 4546.)
  int max_cg_iterations = 10000;
  /// A step's CG stops when its residual is below
  ///   max(0.5 grad_norm_tol, ||g|| min(forcing, ||g||^forcing_power)), g = the step's gradient
  /// (the superlinear forcing of truncated Newton; the floor avoids solving beyond need).
  /// forcing in (0, 1), forcing_power >= 0.
  double forcing = 0.1;
  double forcing_power = 1.0;
  /// First trust-region radius in the preconditioner's norm; 0 = unbounded (a plain Newton
  /// step first: the start is a converged block-coordinate iterate). >= 0.
  double initial_radius = 0.0;
  /// A trial is accepted when its ratio of actual to predicted decrease is above this. [0, 0.25).
  double accept_ratio = 0.05;
  /// A rejected trial is tried again at a quarter of the step, up to this many times, before
  /// the trust region shrinks and CG runs again. >= 0.
  int max_backtracks = 6;
  /// true: every CG solve is preconditioned with factors computed at its own point (each block
  /// refactors its tangent preconditioner at the start and after every accepted step). false:
  /// a block keeps the factor it holds (computed at an earlier point: still symmetric positive
  /// definite, merely less exact, since it depends on the point only through the relative
  /// rotations of the block's poses) and factors only when it holds none. The online steps use
  /// false: their start is a warm one, and the factorizations (with their symbolic analyses)
  /// were a third of their instructions on a generated 1,000-pose city (docs/online.md,
  /// "Newton steps").
  bool refactor_every_step = true;
  /// With refactor_every_step: each block's tangent factor includes the Hessian's multiplier
  /// term (TangentPreconditioner::factorize(X, egrad)), so block Jacobi applies the inverse of
  /// the block's diagonal block of the Riemannian Hessian itself (where that is positive
  /// definite; else the factor without it), and only the coupling across the cut is left to
  /// CG. Without it the factor misses the term that softens a chain's bending modes
  /// (docs/centralized-solver.md). The gain is a CG count (ais2klinik: 4,318 -> 3,166 CG
  /// iterations, 32 -> 27 steps; docs/newton-refine.md).
  bool hessian_multipliers = true;
  /// The preconditioner's coarse correction (two-level additive Schwarz,
  /// distributed/tangent_coarse_space.hpp). kBlocks: block Jacobi plus one rigid motion per
  /// block, Phi A^+ Phi^T r with A = Phi^T Hess f Phi summed once per point (one all-agent sum
  /// per accepted step) and Phi^T r carried in each CG iteration's sum (k(k+1)/2 numbers per
  /// block at k active rows: no extra message step). kNone: block Jacobi alone, whose CG
  /// iterations grow with the chain's length (ais2klinik: 4,540).
  /// kSmoothed: `coarse_aggregates` pieces per block blended over `coarse_smoothing_steps`
  /// measurement hops (the smoothed aggregation of coarse_space.hpp; AgentState::refine_space(),
  /// built from the graph's structure where the agents are set up; blocks where there is none).
  enum class Coarse { kNone, kBlocks, kSmoothed };
  /// Default kNone: the coarse correction cuts CG iterations (parking-garage 889 -> 175) but
  /// costs more per iteration than it saves where it cuts few (ais2klinik in process: 3,410
  /// iterations and 30 CPU-s smoothed, 4,318 and 12 CPU-s without; docs/newton-refine.md).
  Coarse coarse = Coarse::kNone;
  /// How the coarse correction joins block Jacobi B. true: balancing,
  /// C + (I - C H) B (I - H C) with C = Phi A^+ Phi^T (the coarse space's error removed exactly;
  /// (H Phi)^T y rides in the same sum, so still one exchange and one sum an iteration, each
  /// agent keeping its rows of H Phi). false: additive, B + C.
  bool coarse_balancing = true;
  /// Which Hessian the coarse matrix A inverts. true: the Riemannian Hessian, multiplier term
  /// included (A = Phi^T Hess f Phi, the Galerkin matrix). false: its data part only,
  /// Phi^T Proj(2 V Q) Phi, positive semi-definite at every point, as the block factors are
  /// without `hessian_multipliers` (balancing still uses Hess f for its H Phi and A's
  /// products). Why: away from a minimum the multiplier term can make A indefinite or nearly
  /// singular in the pieces' relative motions; its pseudo-inverse then drops the negative
  /// directions and blows up the nearly flat ones, so those motions are short in the
  /// preconditioner's norm the trust region bounds, and the steps were long in f's
  /// (docs/online.md, "Smoothed pieces"). The online steps keep their block factors without
  /// the multipliers and set false; batch refinements keep true.
  bool coarse_multipliers = true;
  /// With coarse_multipliers false: the inverted data-part matrix is summed at every this many
  /// accepted Newton steps and kept for the ones between (only Phi^T g is summed at their
  /// points; the kept matrix is positive semi-definite, so the preconditioner stays positive
  /// definite). Those steps' CGs take the additive form: balancing needs the H Phi columns and
  /// Galerkin matrix of their own point. Why: summing the matrix and the H Phi columns was about
  /// a third of the online steps' CPU on the 5,000-pose grid (docs/online.md). Default 1 (every
  /// accepted step; batch refinements); the online steps set 3. >= 1.
  int coarse_keep_steps = 1;
  /// kSmoothed: pieces per block (>= 1) and smoothing steps of their weights (0..8).
  int coarse_aggregates = 8;
  /// kSmoothed: > 0 gives a block one piece per this many of its poses, 1..coarse_aggregates
  /// (CoarseOptions::poses_per_aggregate; the online steps' `--step-coarse-aggregates auto`);
  /// 0 (the default): coarse_aggregates in every block. >= 0.
  int coarse_poses_per_aggregate = 0;
  int coarse_smoothing_steps = 1;
  /// The blocks a group of linked blocks needs for its pieces to take part in the coarse
  /// correction (TangentCoarseSpace::groups()); a smaller group takes block Jacobi's steps, as
  /// a robot that has met no other does. A connected graph of N blocks is one group, so batch
  /// solves with N >= this are unchanged. Default 2 (every linked group); the online steps set
  /// their own (OnlineOptions::newton_coarse_min_blocks). >= 2.
  int coarse_min_blocks = 2;
  /// Translations re-solved at every trial point: after the retraction moves the poses, the
  /// agents run up to this many iterations of a distributed conjugate gradient on the
  /// translations alone (the rotations fixed, f is quadratic in them: Hessian 2 L, L the
  /// translation Laplacian), block-Jacobi preconditioned with each block's own Laplacian block
  /// (factored once: it does not depend on the point). Why: a Newton step on a long chain bends
  /// it, turning poses by different angles about distant points; no pose-local retraction
  /// places their translations right (lever arms of hundreds of metres on ais2klinik), so the
  /// trust region stayed small and each step ended on its boundary after 150-300 CG iterations.
  /// Each iteration lowers f (CG on a convex quadratic from the retracted point), so any count
  /// is sound. Costs per iteration one exchange and one all-agent sum (2 numbers). >= 0; 0 = off
  /// (no re-solve at all, exact or not).
  int translation_iterations = 50;
  /// The translation CG stops once an iteration lowers f by at most this fraction of the
  /// Newton step's predicted decrease (the rest it could remove is then small against what the
  /// ratio test weighs). (0, 1).
  double translation_tol = 1e-3;
  /// Exact trial translations: where the team's interface has at most this many poses (poses
  /// with a cut measurement: ais2klinik at N = 5 34, city10000 303), the re-solve above is one
  /// exact solve with 2 L by substructuring (distributed/translation_interface_solve.hpp)
  /// instead of the block-Jacobi CG: each block factors its L_BB (interface last) and sends its
  /// Schur complement once per refinement, riding in the start's sum (L does not depend on the
  /// point); every agent factors the interface matrix (this many rows at most, once); a trial
  /// point then costs one all-agent sum (each block's interface residual, its interface poses x
  /// the iterate's rows) and no exchange: the solve's interface values are the neighbours' new
  /// public translations. A block whose L_BB is singular (a pose without measurements) sends
  /// a flag and the team keeps the CG. Why: the CG took 120 iterations (two message steps
  /// each) over ais2klinik's 9 trial points, 80 % of the refinement's 299 message steps
  /// (docs/newton-refine.md, "Exact trial translations"). >= 0; 0 = off (the CG above).
  int translation_interface_max_poses = 2000;
  /// Preconditioner: exact solves with the Hessian through the team's interface
  /// (distributed/interface_solve.hpp) where that interface has at most this many tangent
  /// coordinates (d(d+1)/2 a pose: ais2klinik at N = 5 102, city10000 909); 0 = off. Each
  /// block factors its diagonal block of the Riemannian Hessian (interface last) and broadcasts
  /// its Schur complement and cut couplings once per point (one all-agent message step); the
  /// interface matrix Sigma (as large as this cap) is factored (by agent 0 or by every agent,
  /// `sigma_factoring`) and H^-1 applied exactly (up to the shift below) in each CG iteration,
  /// whose message steps are one exchange and one sum (the interface residual rides in the sum),
  /// and with kShipSolves agent 0's solution. Used at rank d with `coarse` kNone. A block whose
  /// Hessian block is not positive definite (far from a minimiser) factors it without the
  /// multiplier term (then M is the inverse of that modified H); where no block factor or no Sigma
  /// is positive definite, that point's CG runs block Jacobi. Why 1,000: Sigma's factorization
  /// (CHOLMOD supernodal; dense within each block's interface) grows up to size^3 / 3. Chosen
  /// when every agent factored Sigma at every point and received every Schur complement:
  /// city10000's 909 coordinates at N = 5 (cap 1,000 against 500, in process): rounds 142 -> 48,
  /// the refinement's CG 2 iterations, 5.38 against 6.94 billion instructions for the whole solve
  /// (callgrind), same certified optimum; cubicle's 1,572 cut its CG iterations 116 -> 3 but then
  /// doubled the CPU of the whole solve and multiplied the bytes by 8 (4.9 -> 40.6 MB), so it
  /// stayed out, as did torus3D (2,916) and sphere2500 (2,088). With kShipSolves, the default
  /// from ship_solves_min_coordinates, that cost is agent 0's alone (cubicle 4.9 -> 4.8 MB, user
  /// CPU 0.6x, loaded). With kShipSolves, at 3,000 (callgrind, whole solve): cubicle and
  /// sphere2500 0.74x and 0.76x the instructions, torus3D 1.74x (and 7.5x the bytes), so no cap
  /// suits all three and it stays at 1,000 (docs/newton-refine.md, "Cap").
  /// parking-garage (348) and ais2klinik (102) gain 4-9x. >= 0.
  int interface_max_coordinates = 1000;
  /// kIfRoundsSlow: where the interface solves apply (the team's interface within
  /// interface_max_coordinates), the rounds stop at max(the solver's grad_norm_tol,
  /// this) and the refinement always runs. Why: with exact interface solves (and exact trial
  /// translations) a Newton step costs a few message steps even from a rough point, where the
  /// rounds' last decades cost hundreds: in process at N = 5, message steps from gradient 1
  /// against 30: kitti_02 661 -> 125, ais2klinik 121 -> 33, city10000 111 -> 30, the same
  /// certified optimum (docs/newton-refine.md, "Handing over"). 0 = off (the rounds' tail
  /// alone decides). >= 0.
  double auto_interface_grad_tol = 30.0;
  /// Relative shift eta of Sigma (times its largest diagonal entry). Sigma is grounded at one
  /// pose (the gauge, interface_solve.hpp); the shift covers its slight indefiniteness away
  /// from a minimiser. On a failed factorization it is raised 1,000-fold twice, then the same
  /// without grounding, before the fallback. (0, 1e-3].
  double interface_shift = 1e-10;
  /// With the interface solves: true, the CG works on the tangent vectors orthogonal to the
  /// gauge (distributed/gauge_space.hpp): each iteration's z and H z are projected off it, the
  /// projection's sums riding in the iteration's sum, so CG solves the full Newton equation
  /// (the grounded Sigma's inverse, projected, is its preconditioner); false, CG solves the
  /// equation with the grounded pose held and the step is projected off the gauge once.
  /// Why false: on the paper graphs at N = 5 both take the same steps, CG iterations and
  /// message steps, and projecting costs 5 % more instructions (city10000) and 10-27 % more
  /// bytes; from a rough start on a 1,000-pose corridor the grounded CG meets negative
  /// curvature along the gauge (6 steps, one rejected, 36 message steps; projected: 4, 31)
  /// (docs/newton-refine.md, "Gauge").
  bool project_gauge = false;
  /// With the interface solves: the start point's interface shares (each block's Schur
  /// complement and couplings, interface residual of -g and gauge sums; kShipSolves: the
  /// brief ones to the agents other than agent 0) ride in the start's sum (kStatus) instead of
  /// a message step of their own right after it. Each agent factors its block at the start
  /// point before the sum says whether a refinement runs at all: where the start's gradient is
  /// already below grad_norm_tol, or the rows in use on some agent are not the first d (then
  /// the interface step runs as before), that factorization is not used. The same iterates
  /// either way; one message step fewer per refinement (GNC's weighted solves are one
  /// refinement of one Newton step each; docs/newton-refine.md). A core option without a flag:
  /// every agent of a run uses the same value.
  bool interface_in_status = true;
  /// With the interface solves (every agent factoring Sigma, or agent 0 solving with it): where
  /// the model predicts that a trial step will not end the refinement (as kShipFactor's test
  /// below), each agent factors its block at the trial point before the verdict and its whole
  /// interface share there rides in the trial's sum; an accepted trial's CG then starts with no
  /// interface step of its own. A rejected trial's or a last step's factorization is not used
  /// (pending_factors_unused). The same iterates either way; one message step fewer per
  /// accepted step but the last. A core option without a flag, as interface_in_status.
  bool interface_in_trial_sums = true;
  /// Who assembles and factors Sigma, the interface solves' matrix, at each point
  /// (`--refine-sigma`, set_sigma_mode). All three take the same steps, CG iterations and
  /// iterates to the same bits (the same shares in id order, the same factorization and
  /// solves); they differ in CPU, bytes and message steps.
  ///   kEveryAgent (`every`): every agent assembles and factors Sigma at every point and solves
  ///   with it itself.
  ///   kShipFactor (`one`): where the model says a trial step will not end the refinement (its
  ///   predicted decrease above relative_decrease_tol |f|, steps left), each agent factors its
  ///   block at the trial point before the verdict and its share of Sigma rides in the trial's
  ///   sum; at an accepted trial agent 0 alone assembles and factors Sigma and sends the factor
  ///   in the interface step that every point has anyway (the other agents take it as it is:
  ///   the same bits as their own factorization). The start point and a step predicted to be
  ///   the last take the every-agent path. Why not the default: on city10000 at N = 5 it saves
  ///   9.3 % of the refinement's instructions in process (1.95 -> 1.77 G) but sends Sigma's
  ///   factor (1.9 MB) to every agent at each shipped point (DDS bytes 9.1 -> 13.0 MB), and
  ///   over DDS on one 2-core machine the agents' CPU after the rounds did not fall (medians
  ///   of 6 launches 0.85 vs 1.08 CPU-s, load 12-17): what the agents' threads save in
  ///   factorizations their transport spends moving the factor.
  ///   kShipSolves (`solve`, the default): at each point ONE agent (agent 0) receives the
  ///   blocks' Schur complements and couplings (the other agents only the flags, interface
  ///   residuals and gauge sums), assembles and factors Sigma, and for each CG direction solves
  ///   with it and sends each agent its own segment of the solution (a short vector: the
  ///   agent's interface coordinates), one more message step a direction, on which every agent
  ///   waits for agent 0. Where Sigma is smaller than ship_solves_min_coordinates the team
  ///   runs kEveryAgent instead. Why the default: the agents' identical Sigma factorizations
  ///   are redundant CPU, which is wall where agents share processors. city10000 at N = 5 in
  ///   process (callgrind), against kEveryAgent: the whole solve 4.335 -> 3.842 G
  ///   instructions, the refinement 1.948 -> 1.487 G, bytes 14.67 -> 4.72 MB, message steps
  ///   27 -> 30; over DDS on a 2-core machine the agents' CPU after the rounds 0.865 -> 0.730
  ///   CPU-s (medians, load 16-19).
  /// (docs/newton-refine.md, "Who factors Sigma".)
  enum class SigmaFactoring { kEveryAgent, kShipFactor, kShipSolves };
  SigmaFactoring sigma_factoring = SigmaFactoring::kShipSolves;
  /// kShipSolves applies where the team's interface has at least this many tangent
  /// coordinates (Sigma's size; the same on every agent); below it every agent factors Sigma.
  /// Why: Sigma's factorization grows about as its size cubed, the extra message step a CG
  /// direction does not: at city10000's 909 coordinates one factorization is ~37 M
  /// instructions (every agent doing it 553 M over 3 points), at ais2klinik's 102 about
  /// (102 / 909)^3 of that, less than the wait for one more message. >= 0.
  int ship_solves_min_coordinates = 500;
  /// Not a setting but where a run keeps its agents' interface-solve factors from one
  /// refinement to the next (make_interface_analysis_store()); null (the default): each
  /// refinement analyses its factors' patterns afresh. With a store, a refinement whose block
  /// Hessian or Sigma has the pattern of the agent's previous refinement factors it numerically
  /// only: the same factors to the bit, the same iterates. The distributed GNC sets one (its
  /// weighted solves are one refinement each, on layouts that mostly repeat).
  std::shared_ptr<InterfaceAnalysisStore> analyses;
  /// The CoarseOptions that build the kSmoothed space (make_coarse_space).
  CoarseOptions coarse_space_options() const;
  /// Throws InputError naming the bad field.
  void validate() const;
};

/// A store for NewtonRefineOptions::analyses (one per run, shared by its agents).
std::shared_ptr<InterfaceAnalysisStore> make_interface_analysis_store();

/// The `--refine` values as options: "none" (enabled off), "newton" (kAlways) or "auto"
/// (kIfRoundsSlow). One parser for the command line, the coordinator, launch and the agents'
/// assignment. Throws InputError "option --refine: 'v' is not one of newton, auto, none".
void set_refine_mode(NewtonRefineOptions& options, const std::string& mode);

/// The `--refine-sigma` values as options: who factors the interface solves' Sigma. "every"
/// (SigmaFactoring::kEveryAgent), "one" (kShipFactor) or "solve" (kShipSolves). One parser for the
/// command line, the coordinator and the agents' assignment. Throws InputError "<what>: 'v' is not
/// one of every, one, solve".
void set_sigma_mode(NewtonRefineOptions& options, const std::string& mode,
                    const std::string& what = "option --refine-sigma");
/// The `--refine-sigma` value of `options` (set_sigma_mode's inverse).
std::string sigma_mode(const NewtonRefineOptions& options);

/// One trust-region step, identical on every agent.
struct NewtonRefineStep {
  int cg_iterations = 0;
  int translation_iterations = 0;  ///< Of the trial point's translation CG.
  double radius = 0.0;             ///< Trust radius the step was computed in (0 = unbounded).
  /// Length of the step taken, in the radius's (the preconditioner's) norm: the radius itself
  /// where CG stopped on the boundary or at negative curvature.
  double step_norm = 0.0;
  double predicted = 0.0, actual = 0.0;  ///< Decreases of the model and of f.
  bool accepted = false;
  /// residual, boundary, negative_curvature or cap; backtrack: the last CG step scaled down
  /// (cg_iterations 0).
  std::string cg_stop;
  double cost = 0.0;       ///< f after the step (the old one when rejected).
  double grad_norm = 0.0;  ///< ||grad f|| there.
};

/// Where one agent's refinement went: its own thread's CPU seconds by part (start() and the
/// handling of every message that completes a step are charged to exactly one part; storing a
/// message that completes no step is not timed: each reading of the thread's CPU clock is a
/// system call), and the wall from start() to the last step. Per agent (not identical across
/// agents); CPU seconds hold whatever the load.
struct NewtonRefineTimes {
  double setup_s = 0.0;  ///< Start point's sums, the solves' orderings, translation factors.
  /// Each point's factorizations: the interface solves' block factors, Schur complements,
  /// couplings and the gauge's products (or block Jacobi's factor), and the coarse matrix.
  double factor_s = 0.0;
  double sigma_s = 0.0;  ///< Sigma's assembly and factorization (or taking agent 0's), per point.
  double cg_s = 0.0;     ///< CG iterations: preconditioner, Hessian products, sums.
  double trial_s = 0.0;  ///< Trial points: retraction, cost and gradient, verdict.
  double translations_s = 0.0;  ///< Trial translations: exact solves or the translation CG.
  double cpu_s = 0.0;           ///< All of the above.
  double wall_s = 0.0;          ///< start() to the end (waits for the team included).
};

/// Identical on every agent (but `times`).
struct NewtonRefineResult {
  /// grad_norm (reached the tolerance), max_steps, max_cg_iterations or stalled (the trust
  /// region shrank below round-off).
  std::string stop_reason;
  double initial_cost = 0.0, initial_grad_norm = 0.0;
  double cost = 0.0, grad_norm = 0.0;  ///< At the final point.
  int steps = 0, accepted_steps = 0, cg_iterations = 0;
  /// Message steps: neighbour exchanges (CG directions and trial poses) and all-agent sums.
  int exchanges = 0, reductions = 0;
  /// kShipSolves: the CG directions' steps that wait for the agent solving with Sigma.
  int solution_steps = 0;
  /// All together: the refinement's waits for peers (a round of IRBCD is two).
  int message_steps() const { return exchanges + reductions + solution_steps; }
  /// Coarse correction: its unknowns (pieces x generators; 0 without), and how many times its
  /// matrix was summed (one all-agent sum each, counted in `reductions`).
  int coarse_unknowns = 0, coarse_assemblies = 0;
  /// Accepted steps that kept the coarse matrix and took Phi^T g at their point from the
  /// trial's sum (no coarse message step of their own).
  int coarse_gradients_carried = 0;
  /// Accepted steps whose interface shares at their point came with the trial's sum
  /// (interface_in_trial_sums: no interface message step of their own).
  int interface_shares_carried = 0;
  /// Iterations of the trial points' translation solves (each one exchange and one sum,
  /// counted in `exchanges` and `reductions`).
  int translation_iterations = 0;
  /// Exact trial translations (translation_interface_max_poses): the team's interface poses
  /// (0: not used, the CG above ran) and the exact solves (one all-agent sum each, counted in
  /// `reductions`; none of them in translation_iterations).
  int translation_interface_poses = 0, translation_solves = 0;
  /// Interface solves (interface_max_coordinates): the team's interface in tangent coordinates
  /// (0: not used), the points where Sigma was factored (one all-agent message step each,
  /// counted in `reductions`, but where the shares rode in the sum before: the start's with
  /// interface_in_status, interface_shares_carried) and where it could not be (that step's CG
  /// ran block Jacobi).
  int interface_coordinates = 0, interface_factorizations = 0, interface_fallbacks = 0;
  /// This agent's own assemblies and factorizations of Sigma (points), the points whose Sigma it
  /// took from agent 0's factor (kShipFactor), and the block factorizations at trial points that
  /// were not used (a rejected trial, or the refinement stopped there).
  int sigma_factorizations = 0, sigma_imports = 0, pending_factors_unused = 0;
  /// This agent's symbolic analyses of its interface solves' factors (its block's, Sigma's):
  /// one per pattern its factors did not hold (NewtonRefineOptions::analyses).
  int interface_analyses = 0;
  std::vector<NewtonRefineStep> trace;
  NewtonRefineTimes times;  ///< This agent's.
};

/// Message steps of several refinements (the sum of their message_steps()).
int message_steps(const std::vector<NewtonRefineResult>& refines);

class NewtonRefineProtocol : public AgentProcess {
 public:
  /// Protocol steps (on the wire: the solve stage's phase base + these; RoundProtocol uses
  /// 0..5 in the same stage).
  enum Step : std::uint32_t {
    kStatus = 60,     ///< Cost share, ||g||^2 and active rows at the start point; the translation
                      ///< Schur complement (exact trial translations).
    kDirection = 61,  ///< Public entries of the preconditioned residual z.
    kSums = 62,       ///< CG's <r, z>, <z, H z>, <r, r>.
    kTrial = 63,      ///< Public poses of the trial point.
    kTrialSums = 64,  ///< Cost share and ||g||^2 at the trial point.
    kCoarse = 65,     ///< The coarse matrix's share and Phi^T g at the current point.
    kTranslationDirection = 66,  ///< Trial translations: public entries of the CG's z.
    kTranslationSums = 67,       ///< Trial translations: <r, z>, <z, H z>.
    kInterface = 68,             ///< Interface solves: each block's Schur complement and couplings.
    kTranslationSolve = 69,      ///< Exact trial translations: each block's interface residual.
    kSolution =
        70  ///< kShipSolves: Sigma's solve, each agent's segment, from the agent holding it.
  };
  /// The last of the steps: [kStatus, kLastStep] are the refinement's.
  static constexpr std::uint32_t kLastStep = kSolution;
  static bool is_refine_step(std::uint32_t step) { return step >= kStatus && step <= kLastStep; }

  /// `state`: the agent at the point to refine (Y, and Yn = the neighbours' public poses of the
  /// same point). It must outlive the protocol; on done() its sequences are reset to the final
  /// point (AgentState::reset_iterate).
  NewtonRefineProtocol(AgentState& state, const BlockLayout& layout,
                       const NewtonRefineOptions& options);
  ~NewtonRefineProtocol() override;

  std::vector<OutgoingMessage> start() override;
  std::vector<OutgoingMessage> handle(const ProtocolMessage& message) override;
  bool done() const override { return done_; }
  std::size_t messages_needed() const override;
  /// The current message step's missing senders (a stalled run names them).
  std::optional<AwaitedMessages> awaited() const override;
  const NewtonRefineResult& result() const { return result_; }
  /// Called with each trial point, its translations solved, as the trial's sums go out: the own
  /// block at the iterate's rank (rows no agent uses are zero), exactly the block the agent
  /// holds if the trial is accepted. A caller that must exchange the accepted point's poses can
  /// send them beside the sums instead of in a message step of its own (robust GNC's weighted
  /// solves).
  void set_trial_observer(std::function<void(const Eigen::MatrixXd&)> observer) {
    trial_observer_ = std::move(observer);
  }
  /// Before start(): ||grad f|| at the start point as the team last summed it (the rounds' last
  /// status; the same on every agent). At or below grad_norm_tol the refinement will stop at
  /// its start's sum, so the interface shares (interface_in_status) stay out of that sum: a
  /// robust run's final solve that only checks its gradient sent them for nothing (CSAIL, 25 %
  /// random outliers: 1.4 MB). Only bytes and work depend on it, never the iterates.
  void set_start_grad_norm(double grad_norm) { start_grad_norm_ = grad_norm; }

  /// Where the refinement is, for progress reports: the trust-region step being computed
  /// (1-based, rejected ones and backtracks counted), the CG iterations of that step so far and
  /// ||grad f|| at the current point. nullopt until the start point's sums are in.
  struct Progress {
    std::uint32_t step = 0, cg_iteration = 0;
    double grad_norm = 0.0;
  };
  std::optional<Progress> progress() const {
    if (message_round_ == 0) return std::nullopt;
    return Progress{static_cast<std::uint32_t>(result_.steps + 1),
                    static_cast<std::uint32_t>(step_.cg_iterations), gnorm_};
  }

 private:
  using SigmaFactoring = NewtonRefineOptions::SigmaFactoring;
  void pump(std::vector<OutgoingMessage>& out);
  void send_public(const Eigen::MatrixXd& v, std::uint32_t step, std::vector<OutgoingMessage>& out);
  void broadcast(std::uint32_t step, const std::vector<double>& values,
                 std::vector<OutgoingMessage>& out);
  // The neighbours' public entries of a vector sent in one step, into vn (zero elsewhere).
  void neighbours_into(const MessageGate::Inbox& inbox, Eigen::MatrixXd& vn) const;
  // Local pieces at (X_, Xn_): egrad_, g_ and the cost share.
  double evaluate_point();
  Eigen::MatrixXd hessian(const Eigen::MatrixXd& v, const Eigen::MatrixXd& vn);
  // The same at another point X (egrad its Euclidean gradient).
  Eigen::MatrixXd hessian_at(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad,
                             const Eigen::MatrixXd& v, const Eigen::MatrixXd& vn);
  void after_status(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // Whether this agent's rows in use (own and neighbour poses) are all below d.
  bool nonzero_rows_within(Eigen::Index d) const;
  // The point and its gradients on rows_ only (rows_taken_).
  void take_rows();
  void begin_cg(std::vector<OutgoingMessage>& out);
  // The coarse matrix's share at the current point, summed by every agent (kCoarse).
  void send_coarse(std::vector<OutgoingMessage>& out);
  void after_coarse(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // Interface solves: this block's factor and share of Sigma at the current point (kInterface),
  // then every agent's Sigma.
  void send_interface(std::vector<OutgoingMessage>& out);
  void after_interface(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // send_interface()'s message values: this block's factor and share of Sigma at the current
  // point, its interface residuals and the gauge's sums (sets the point's gauge and forward
  // solves of -g).
  std::vector<double> interface_share(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                      const Eigen::MatrixXd& egrad, const Eigen::MatrixXd& g,
                                      bool pending);
  // The point's gauge and forward solves (gauge_, gauge_hv_, iy_g_, gauge_fv_, gauge_fhv_)
  // swapped with the trial point's (interface_in_trial_sums).
  void swap_point_parts();
  // The accepted trial's interface shares, carried by its sum: the step kInterface would be.
  void use_carried_shares(std::vector<OutgoingMessage>& out);
  // Whether this trial's sum carries the whole interface share at the trial point
  // (interface_in_trial_sums): the same inputs, so the same answer, on every agent.
  bool ship_trial_interface() const;
  // kShipSolves: what of a share the agents other than the holder receive.
  std::vector<double> brief_share(const std::vector<double>& values) const;
  // kShipSolves: `full` to the holder (and this agent's own gate), `brief` to the others.
  void send_to_holder(std::uint32_t step, const std::vector<double>& full,
                      const std::vector<double>& brief, std::vector<OutgoingMessage>& out);
  // after_interface() on the team's shares (every agent's, in id order), wherever they came in.
  void use_interface_shares(const std::vector<std::pair<int, const std::vector<double>*>>& shares,
                            std::vector<OutgoingMessage>& out);
  // The interface solves where they apply to the team's interface (its size within the cap),
  // null elsewhere; the layout is the same on every agent, so is the answer.
  std::unique_ptr<InterfaceSolve> make_interface();
  // v's columns of the interface solve's grounded pose set to zero (where this block has it).
  void ground_pose(Eigen::MatrixXd& v) const;
  // The gauge's numbers in each interface share: V^T V, V^T H V (k x k each) and V^T g.
  std::size_t gauge_share_size() const;
  // The CG step's part orthogonal to the gauge, with its model's <g, s> and <s, H s>.
  void project_step_off_gauge();
  // Projecting the gauge: z, H z (and H z's interface residuals) of this iteration projected
  // off V, and the iteration's sums t (as after_sums reads them) corrected to theirs.
  void project_iteration_off_gauge(std::vector<double>& t);
  // CG from s = 0 at the current point (the coarse matrix, if any, is current).
  void start_cg(std::vector<OutgoingMessage>& out);
  // x's entries at the coarse unknowns this agent touches (coarse_hphi_'s columns).
  Eigen::VectorXd touched_of(const Eigen::VectorXd& x) const;
  // The block preconditioner for the next CG solve (options_.refactor_every_step).
  void prepare_preconditioner();
  void send_direction(std::vector<OutgoingMessage>& out);
  // kShipSolves: a share's trailing interface residuals (this block's), in values.
  std::size_t share_tail() const;
  // kShipSolves, on the holder: u = Sigma^-1 rhat of the current residual, each agent's segment
  // sent to it (kSolution, after the flag and grounding); everyone waits for it. With ok false
  // (no positive definite Sigma at this point), the flag 0 alone.
  void send_solution(bool ok, std::vector<OutgoingMessage>& out);
  void after_solution(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // After a point's Sigma: whether the CG uses it (ok), the gauge's sums, fallback otherwise.
  void take_interface_verdict(bool ok);
  // start_cg()'s state (s = 0, r = -g, the interface residuals) without the first direction.
  void reset_cg();
  void after_direction(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void after_sums(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void try_step(const std::string& cg_stop, std::vector<OutgoingMessage>& out);
  void after_trial(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void after_trial_sums(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  void finish(const std::string& why);
  // The trial point's translations re-solved for its rotations (translation_iterations).
  void start_translations(std::vector<OutgoingMessage>& out);
  void send_translation_direction(std::vector<OutgoingMessage>& out);
  void after_translation_direction(const MessageGate::Inbox& inbox,
                                   std::vector<OutgoingMessage>& out);
  void after_translation_sums(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // Exact trial translations: the team's interface solve, then the trial's sums.
  void after_translation_solve(const MessageGate::Inbox& inbox, std::vector<OutgoingMessage>& out);
  // The trial point's cost share and ||g||^2 (kTrialSums), its neighbours' poses set; with
  // ship_trial_shares(), the block's share of Sigma at the trial point after them.
  void send_trial_sums(std::vector<OutgoingMessage>& out);
  // Whether this trial's sum carries the Sigma shares (kShipFactor): the same inputs,
  // so the same answer, on every agent.
  bool ship_trial_shares() const;
  // Agent 0 with the shares in hand: Sigma assembled and factored, its factor's message values.
  std::vector<double> factor_shipped_sigma();

  // Charges this thread's CPU time since the last switch to the current part, then makes
  // `part` (a field of result_.times, or nullptr between messages) the current one.
  void charge_to(double* part);

  AgentState& state_;
  const BlockLayout& layout_;
  NewtonRefineOptions options_;
  BlockProblem problem_;  // own copy: its neighbour poses are set to directions
  MessageGate gate_;
  double* timed_part_ = nullptr;  // charge_to()'s current part and its start (thread CPU s)
  double timed_since_ = 0.0;
  double wall_start_ = 0.0;          // steady clock at start(), s
  std::uint32_t message_round_ = 0;  // one per message step, the same on every agent
  std::vector<int> everyone_;        // the agents every reduction waits for: 0 .. N-1
  std::vector<Eigen::Index> rows_;   // active rows (non-zero on some agent)
  // The point and its local pieces; the trial point.
  Eigen::MatrixXd X_, Xn_, egrad_, g_, Xt_, Xtn_, egrad_t_, g_t_;
  double f_ = 0.0, gnorm_ = 0.0;
  // CG on H s = -g: s, r, z = P r, w = H z, p, q = H p.
  Eigen::MatrixXd s_, r_, z_, w_, p_, q_;
  Eigen::MatrixXd zn_;  // the neighbours' z, kept between CG steps for its storage
  // Its scalars (iterations, the previous gamma and alpha, the preconditioned norms of s, p).
  std::unique_ptr<PipelinedCg> cg_;
  double model_ = 0.0;           // m(s) = <g, s> + <s, H s> / 2
  double gs_ = 0.0, sHs_ = 0.0;  // <g, s>, <s, H s> of the CG step
  Eigen::MatrixXd s_full_;       // the CG step; a backtrack tries scale_ of it
  double scale_ = 1.0;
  int backtracks_ = 0;
  double cg_target_ = 0.0;     // residual norm that ends the CG
  double radius_ = 0.0;        // 0 = unbounded
  bool refactor_due_ = false;  // a step was accepted since the last factorization
  // Coarse correction (options_.coarse): the space at the active rows, the pseudo-inverse of
  // its Galerkin matrix, Phi^T g at the current point, Phi^T r and Phi^T q of the CG
  // (recurrences, as r and q: Phi^T w rides in each iteration's sum).
  std::unique_ptr<TangentCoarseSpace> coarse_;
  // Balancing: the own rows of H Phi, one column per touched unknown, on its non-zero poses.
  std::unique_ptr<CoarseHessianColumns> coarse_hphi_;
  Eigen::VectorXd coarse_hy_;  // balancing: this agent's share of (H Phi)^T y
  Eigen::VectorXd coarse_g_, coarse_r_, coarse_q_;
  bool coarse_due_ = true;  // the point changed since the coarse matrix was summed
  // Kept coarse matrix: accepted steps since it was summed, and whether this CG balances
  // (only with the matrix summed at its own point: balancing needs that point's H Phi).
  int coarse_kept_steps_ = 0;
  bool coarse_fresh_ = true;
  // Whether the current trial's sum carries Phi^T g at the trial point (an accepted one keeps
  // the matrix): that step then sends no coarse sum.
  bool trial_coarse_g_ = false;
  bool ship_trial_coarse_gradient() const;
  bool balancing() const { return options_.coarse_balancing && coarse_fresh_; }
  // Interface solves (options_.interface_max_coordinates): the solver, whether Sigma is due
  // (the point changed) and whether this point's CG uses it; y = L^-1 J^T of r, q, w and of -g
  // (the block's forward solves) and the team's interface residuals of r, q and -g, carried by
  // CG's recurrences (the one of H z rides in the iteration's sum).
  std::unique_ptr<InterfaceSolve> interface_;
  bool interface_due_ = true, use_interface_ = false;
  // options_.interface_in_status: the start's sum has the interface shares' field (the same on
  // every agent); this agent's point is on the first d rows already (its share computed there).
  bool status_shares_ = false, rows_taken_ = false;
  // interface_in_trial_sums: whether the current trial's sum carries its interface shares, and
  // whether the accepted trial's (next_shares_) are in hand for the next CG; the trial point's
  // gauge and forward solves meanwhile (swap_point_parts()).
  bool trial_interface_ = false, interface_carried_ = false;
  std::unique_ptr<GaugeSpace> trial_gauge_;
  std::vector<Eigen::MatrixXd> trial_gauge_hv_;
  Eigen::VectorXd trial_iy_g_;
  Eigen::MatrixXd trial_gauge_fv_, trial_gauge_fhv_;
  double start_grad_norm_ = std::numeric_limits<double>::quiet_NaN();  // NaN: not known
  // kShipFactor: whether the current trial's sum carries the shares; the team's shares at the
  // accepted trial (id order), in hand for the next interface step (shares_ready_).
  bool trial_shares_ = false, shares_ready_ = false;
  std::vector<std::vector<double>> next_shares_;
  // kShipSolves: the point's Sigma verdict is the holder's, not yet known here (it comes with
  // the point's first solution).
  bool verdict_due_ = false;
  // The agent that assembles and factors Sigma for the team (kShipFactor, kShipSolves): always
  // the same one, so its pattern and symbolic analysis are laid out once.
  static constexpr int kSigmaHolder = 0;
  Eigen::VectorXd iy_r_, iy_q_, iy_w_, iy_g_, ir_, iq_, ir_g_;
  // The gauge with the interface solves (distributed/gauge_space.hpp): its basis V and H V at
  // the point, the sums V^T V, V^T H V and V^T g (in the interface matrix's sum), and the
  // CG's V^T p, V^T H p, V^T s, V^T H s by recurrence (V^T z, V^T H z ride in its sums).
  std::unique_ptr<GaugeSpace> gauge_;
  std::vector<Eigen::MatrixXd> gauge_hv_;
  Eigen::MatrixXd gauge_vv_, gauge_vhv_;
  Eigen::VectorXd gauge_vg_, gauge_vp_, gauge_vhp_, gauge_vs_, gauge_vhs_;
  bool use_gauge_ = false;
  // options_.project_gauge at this point (with use_gauge_): the forward solves F(V), F(H V)
  // (own, one column each), the team's interface residuals R(V), R(H V) (team_size x k) and
  // (H V)^T (H V); the projection's coefficients a (of z) and b (of H z) per iteration.
  bool project_gauge_ = false;
  Eigen::MatrixXd gauge_fv_, gauge_fhv_, gauge_rv_, gauge_rhv_, gauge_hvhv_;
  // Translation solve at the trial point: the own block's translation Laplacian factor, CG
  // state (x the translation change, in the pose layout with zero rotation columns).
  std::unique_ptr<TranslationPreconditioner> translation_preconditioner_;
  bool translations_solved_ = false;  // the current trial's translations are re-solved
  Eigen::MatrixXd tx_, tr_, tz_, tzn_, tw_, tp_, tq_;
  std::unique_ptr<PipelinedCg> tcg_;
  // Exact trial translations (options_.translation_interface_max_poses): the solve (in use once
  // ready()) and the forward solve of the current trial's right-hand side.
  std::unique_ptr<TranslationInterfaceSolve> translation_solve_;
  Eigen::MatrixXd ty_;
  NewtonRefineStep step_;
  std::function<void(const Eigen::MatrixXd&)> trial_observer_;
  bool done_ = false;
  NewtonRefineResult result_;
};

}  // namespace tessera
