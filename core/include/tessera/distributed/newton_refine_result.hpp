#pragma once
// What a distributed Newton refinement did (newton_refine.hpp): its stop, steps, CG iterations,
// message steps by kind and the per-agent CPU by part. Identical on every agent but `times`.

#include <string>
#include <vector>

namespace tessera {

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
  /// Of those, the solves whose u came from agent 0's factor (translation_one_factor_min_poses;
  /// each one more message step, counted in `reductions`).
  int translation_solutions_received = 0;
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

}  // namespace tessera
