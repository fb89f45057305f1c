#pragma once
// The distributed Newton refinement's options (newton_refine.hpp runs it): when it runs, its
// preconditioner (interface solves, block Jacobi, coarse correction), who factors Sigma, the
// trust region's caps and the shares that ride in other messages; and the `--refine` /
// `--refine-sigma` parsers shared by the command line, the coordinator and the agents.

#include <memory>
#include <string>
#include <tessera/distributed/coarse_correction.hpp>

namespace tessera {

class InterfaceAnalysisStore;

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
  /// Without refactor_every_step: a block whose held factor was grown (AgentState::extend
  /// appended new poses to it, TangentPreconditioner::grow) builds a new one at the first
  /// accepted step's point instead of keeping it, so only the first CG runs on the grown factor.
  /// Why: an online step's first Newton point is the first estimate near the new optimum, and
  /// building the grown blocks' factors before its CG was most of the CPU until that point on a
  /// 50,000-pose grid (OnlineOptions::first_step_on_grown_factors, off by default there for
  /// the cost of growing; docs/online.md). Default false: blocks keep what they hold.
  bool refactor_grown_factors = false;
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
  /// Exact trial translations from this many interface poses on: only agent 0 factors their
  /// Sigma; each trial's residuals go to it and it sends every agent u (one more message step a
  /// trial, the same u to the bit). Below, every agent factors Sigma and one all-agent sum gives
  /// each u. Why: the factor (city10000 at N = 5: 303 rows, about 11 M instructions) was repeated
  /// on every agent, 55 M instructions over five. >= 0.
  int translation_one_factor_min_poses = 200;
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

}  // namespace tessera
