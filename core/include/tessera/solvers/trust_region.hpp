#pragma once
// Riemannian trust-region method (RTR) with truncated, preconditioned conjugate gradients
// (Steihaug–Toint) for a BlockProblem on its lifted manifold. Used by the centralized
// solver (many iterations) and by the distributed block updates (one or a few iterations).

#include <Eigen/Core>
#include <functional>
#include <string>
#include <tessera/problem/block_problem.hpp>
#include <tessera/solvers/block_preconditioner.hpp>
#include <vector>

namespace tessera {

struct TrustRegionOptions {
  int max_iterations = 500;         ///< Outer iterations (>= 1).
  int max_inner_iterations = 1000;  ///< tCG iterations per outer iteration (>= 1).
  double grad_norm_tol = 1e-6;      ///< Stop when ||grad f|| <= this (absolute, >= 0).
  /// Also stop when ||grad f|| <= this times its value at X0 (relative, in [0, 1); 0 = off).
  double relative_grad_tol = 0.0;
  /// Stop after this many accepted steps (>= 0; 0 = no limit). Rejected steps do not count,
  /// only max_iterations bounds them: the distributed block updates ask for a number of
  /// accepted steps within a budget of attempts.
  int max_accepted_steps = 0;
  /// Stop when an accepted step decreases f by less than this fraction of f (>= 0).
  double rel_cost_decrease_tol = 1e-12;
  /// A second gradient stop that needs both norms small (absolute, >= 0; the stop is off while
  /// either is 0): ||grad f|| <= paired_grad_norm_tol and ||P grad f|| <=
  /// preconditioned_grad_norm_tol, P the preconditioner (identity when none). ||P grad f||
  /// approximates the Newton step, so the pair says "the gradient is small and so is the step it
  /// would still cause", which does not depend on how the weights scale the gradient.
  double paired_grad_norm_tol = 0.0;
  double preconditioned_grad_norm_tol = 0.0;
  /// The same gradient bound paired with the model's predicted decrease instead (in [0, 1);
  /// 0 = off): stop before a step when ||grad f|| <= paired_grad_norm_tol and 1/2 <P grad f,
  /// grad f> <= this fraction of f. ||P grad f|| with an almost unregularised P is inflated by
  /// the soft modes of long lever arms (parking-garage: 0.26 where f is 1.2e-8 f above f*); the
  /// decrease weighs each mode by its gradient and is relative to f, as the decrease tests are.
  double paired_predicted_rel_decrease_tol = 0.0;
  /// Stop after an accepted step whose rotation part (the Stiefel columns of the update) has a
  /// Frobenius norm below this (>= 0; 0 = off). Translations are left out: they are in the
  /// graph's length unit, rotations are not.
  double step_norm_tol = 0.0;
  /// Stop before a step when the decrease the model's Newton step would bring, 1/2 <P grad f,
  /// grad f>, is below this fraction of f (in [0, 1); 0 = off). This is the relative-decrease stop
  /// taken before the step instead of after it: the step that would only confirm convergence is
  /// not computed. With P below the inverse Hessian the estimate is low by P's error.
  /// When on, the after-step test of rel_cost_decrease_tol also needs this prediction to hold
  /// (a small step does not end the run while the model still predicts more).
  double predicted_rel_decrease_tol = 0.0;
  double initial_radius = 0.0;  ///< <= 0: set from the first preconditioned gradient.
  /// With initial_radius <= 0 the radius is this times sqrt(<P g, g>) (the preconditioned
  /// gradient norm: the length of the Newton step when P is the exact inverse Hessian); > 0.
  double initial_radius_scale = 1.0;
  double max_radius = 1e12;  ///< > 0.
  double tcg_kappa = 0.1;    ///< Linear convergence target of tCG, in (0, 1).
  double tcg_theta = 1.0;    ///< Superlinear exponent of tCG, in (0, 1].
  /// Near the solution, the linear forcing term to use instead of tcg_kappa (in [0, 1); 0 = off):
  /// once ||grad f|| <= near_relative_grad x its value at X0 (in [0, 1]). Far from it a loose
  /// kappa keeps steps short where the model is poor; near it a tighter one makes each costly
  /// step count.
  double tcg_kappa_near = 0.0;
  double near_relative_grad = 1e-2;
  double acceptance_ratio = 1e-4;  ///< Minimum rho to accept a step, in [0, 0.25).
  double max_time_s = 1e9;         ///< Wall-clock budget, seconds (> 0).
  bool record_trace = true;
  /// Retraction R_X(V) to use instead of the manifold's (its SVD polar factor per pose); empty:
  /// the manifold's. The distributed block updates pass a cheaper, equally exact projection.
  std::function<Eigen::MatrixXd(const Eigen::MatrixXd& X, const Eigen::MatrixXd& V)> retraction;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

struct TrustRegionIteration {
  int iteration;
  double cost;
  double grad_norm;
  double radius;
  double rho;
  int inner_iterations;
  bool accepted;
  double elapsed_s;
  /// 1/2 <P grad f, grad f> at the iterate after this step (NaN unless predicted_rel_decrease_tol
  /// is on).
  double predicted_decrease;
};

struct TrustRegionResult {
  Eigen::MatrixXd X;
  double cost = 0.0;
  /// problem.cost_share(X), evaluated with the cost (the next round's status reuses it).
  double cost_share = 0.0;
  double grad_norm = 0.0;
  int iterations = 0;
  int total_inner_iterations = 0;
  std::string stop_reason;
  std::vector<TrustRegionIteration> trace;
};

/// Optional map applied to X0 and to every trial point after the retraction; it must keep
/// the point on the manifold and must not increase the cost. The centralized solver passes
/// the exact translation solve (solvers/translation_elimination.hpp).
using PointRefinement = std::function<void(Eigen::MatrixXd&)>;

/// Minimises problem.cost over the lifted manifold starting from X0 (on the manifold).
/// `preconditioner` may be null (identity); `refine` may be null (none).
TrustRegionResult solve_trust_region(const BlockProblem& problem, const Eigen::MatrixXd& X0,
                                     const TrustRegionOptions& options,
                                     const RiemannianPreconditioner* preconditioner = nullptr,
                                     const PointRefinement* refine = nullptr);

}  // namespace tessera
