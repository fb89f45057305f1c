#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <tessera/solvers/trust_region.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

#include "util/frobenius_inner.hpp"

namespace tessera {

void TrustRegionOptions::validate() const {
  auto fail = [](const std::string& field, const std::string& why) {
    throw InputError("TrustRegionOptions." + field + " " + why);
  };
  if (max_iterations < 1) fail("max_iterations", "must be >= 1");
  if (max_inner_iterations < 1) fail("max_inner_iterations", "must be >= 1");
  if (!(grad_norm_tol >= 0)) fail("grad_norm_tol", "must be >= 0");
  if (!(relative_grad_tol >= 0 && relative_grad_tol < 1))
    fail("relative_grad_tol", "must be in [0, 1)");
  if (max_accepted_steps < 0) fail("max_accepted_steps", "must be >= 0");
  if (!(rel_cost_decrease_tol >= 0)) fail("rel_cost_decrease_tol", "must be >= 0");
  if (!(paired_grad_norm_tol >= 0)) fail("paired_grad_norm_tol", "must be >= 0");
  if (!(preconditioned_grad_norm_tol >= 0)) fail("preconditioned_grad_norm_tol", "must be >= 0");
  if (!(paired_predicted_rel_decrease_tol >= 0 && paired_predicted_rel_decrease_tol < 1))
    fail("paired_predicted_rel_decrease_tol", "must be in [0, 1)");
  if (!(step_norm_tol >= 0)) fail("step_norm_tol", "must be >= 0");
  if (!(predicted_rel_decrease_tol >= 0 && predicted_rel_decrease_tol < 1))
    fail("predicted_rel_decrease_tol", "must be in [0, 1)");
  if (!(max_radius > 0)) fail("max_radius", "must be > 0");
  if (!(initial_radius_scale > 0 && std::isfinite(initial_radius_scale)))
    fail("initial_radius_scale", "must be finite and > 0");
  if (!(tcg_kappa > 0 && tcg_kappa < 1)) fail("tcg_kappa", "must be in (0, 1)");
  if (!(tcg_kappa_near >= 0 && tcg_kappa_near < 1)) fail("tcg_kappa_near", "must be in [0, 1)");
  if (!(near_relative_grad >= 0 && near_relative_grad <= 1))
    fail("near_relative_grad", "must be in [0, 1]");
  if (!(tcg_theta > 0 && tcg_theta <= 1)) fail("tcg_theta", "must be in (0, 1]");
  if (!(acceptance_ratio >= 0 && acceptance_ratio < 0.25))
    fail("acceptance_ratio", "must be in [0, 0.25)");
  if (!(max_time_s > 0)) fail("max_time_s", "must be > 0");
}

namespace {

// Frobenius norm of the Stiefel columns of a tangent vector (pose i: columns (d+1)i .. (d+1)i+d-1).
double rotation_norm(const Eigen::MatrixXd& V, int d) {
  double sq = 0.0;
  for (Eigen::Index c = 0; c + d < V.cols() + 1; c += d + 1) sq += V.middleCols(c, d).squaredNorm();
  return std::sqrt(sq);
}

struct TcgOutcome {
  Eigen::MatrixXd eta;
  Eigen::MatrixXd Heta;
  int iterations = 0;
  bool hit_boundary = false;
  /// Ended because the preconditioner changes at its next application (the step is discarded).
  bool preconditioner_changed = false;
};

// Steihaug–Toint truncated CG on the model m(eta) = <g, eta> + 1/2 <H eta, eta>, with the
// trust region measured in the preconditioner's norm.
TcgOutcome truncated_cg(const BlockProblem& problem, const LiftedManifold& M,
                        const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad,
                        const Eigen::MatrixXd& grad, double radius, const TrustRegionOptions& opt,
                        const RiemannianPreconditioner* precon, const Eigen::MatrixXd* precon_grad,
                        double kappa) {
  auto precondition = [&](const Eigen::MatrixXd& v) { return precon ? precon->apply(M, X, v) : v; };
  TcgOutcome out;
  out.eta = Eigen::MatrixXd::Zero(X.rows(), X.cols());
  out.Heta = out.eta;
  Eigen::MatrixXd r = grad;
  double r0_norm = std::sqrt(frobenius_inner(r, r));
  // The caller may already hold the preconditioned gradient (it sets the initial radius).
  Eigen::MatrixXd z = precon_grad ? *precon_grad : precondition(r);
  double z_r = frobenius_inner(z, r);
  double d_Pd = z_r, e_Pd = 0.0, e_Pe = 0.0;
  Eigen::MatrixXd delta = -z;
  const double radius_sq = radius * radius;
  for (int j = 0; j < opt.max_inner_iterations; ++j) {
    out.iterations = j + 1;
    Eigen::MatrixXd Hdelta = problem.hessian_vector(X, egrad, delta);
    const double d_Hd = frobenius_inner(delta, Hdelta);
    const double alpha = z_r / d_Hd;
    const double e_Pe_new = e_Pe + 2.0 * alpha * e_Pd + alpha * alpha * d_Pd;
    if (d_Hd <= 0 || e_Pe_new >= radius_sq) {
      // Follow delta to the boundary of the trust region.
      const double tau =
          (-e_Pd + std::sqrt(std::max(0.0, e_Pd * e_Pd + d_Pd * (radius_sq - e_Pe)))) / d_Pd;
      out.eta += tau * delta;
      out.Heta += tau * Hdelta;
      out.hit_boundary = true;
      return out;
    }
    e_Pe = e_Pe_new;
    out.eta += alpha * delta;
    out.Heta += alpha * Hdelta;
    r += alpha * Hdelta;
    r = M.tangent_project(X, std::move(r));  // keep rounding errors from leaving the tangent space
    const double r_norm = std::sqrt(frobenius_inner(r, r));
    if (r_norm <= r0_norm * std::min(std::pow(r0_norm, opt.tcg_theta), kappa)) return out;
    // CG needs one fixed preconditioner: the caller computes the step again with the new one.
    if (precon && precon->changes_at_next_apply()) {
      out.preconditioner_changed = true;
      return out;
    }
    z = precondition(r);
    const double z_r_old = z_r;
    z_r = frobenius_inner(z, r);
    const double beta = z_r / z_r_old;
    delta = -z + beta * delta;
    e_Pd = beta * (e_Pd + alpha * d_Pd);
    d_Pd = z_r + beta * beta * d_Pd;
  }
  return out;
}

}  // namespace

TrustRegionResult solve_trust_region(const BlockProblem& problem, const Eigen::MatrixXd& X0,
                                     const TrustRegionOptions& options,
                                     const RiemannianPreconditioner* preconditioner,
                                     const PointRefinement* refine) {
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const LiftedManifold M = problem.manifold(static_cast<int>(X0.rows()));
  TrustRegionResult res;
  res.X = X0;
  if (refine) (*refine)(res.X);
  double f_share = 0.0;
  double f = problem.cost(res.X, &f_share);
  Eigen::MatrixXd egrad = problem.euclidean_gradient(res.X);
  Eigen::MatrixXd grad = M.tangent_project(res.X, egrad);
  double grad_norm = std::sqrt(frobenius_inner(grad, grad));
  const double grad_norm0 = grad_norm;
  const double grad_tol = std::max(options.grad_norm_tol, options.relative_grad_tol * grad_norm);
  int accepted_steps = 0;
  double radius = options.initial_radius;
  // The preconditioned gradient at the current point, when computed for the initial radius:
  // the first tCG iteration starts from the same vector (one solve fewer per block update).
  Eigen::MatrixXd precon_grad;
  bool have_precon_grad = false;
  if (radius <= 0) {
    precon_grad = preconditioner ? preconditioner->apply(M, res.X, grad) : grad;
    have_precon_grad = true;
    radius = std::max(1e-10, options.initial_radius_scale *
                                 std::sqrt(std::max(0.0, frobenius_inner(precon_grad, grad))));
  }
  bool reset_radius = false;
  bool recomputed_here = false;  // a step at the current point was computed again
  auto ensure_precon_grad = [&] {
    if (have_precon_grad) return;
    precon_grad = preconditioner ? preconditioner->apply(M, res.X, grad) : grad;
    have_precon_grad = true;
  };
  // Both stops below need the preconditioned gradient only when they are on; the next tCG starts
  // from the same vector, so computing it costs nothing extra.
  const bool paired_stop =
      options.paired_grad_norm_tol > 0 && options.preconditioned_grad_norm_tol > 0;
  auto paired_met = [&] {
    if (!paired_stop || grad_norm > options.paired_grad_norm_tol) return false;
    ensure_precon_grad();
    return std::sqrt(frobenius_inner(precon_grad, precon_grad)) <=
           options.preconditioned_grad_norm_tol;
  };
  // 1/2 <P g, g> is the decrease of the model's Newton step when P is the inverse Hessian: what
  // the next step can still gain.
  auto predicted_decrease = [&] {
    ensure_precon_grad();
    return 0.5 * std::max(0.0, frobenius_inner(precon_grad, grad));
  };
  res.stop_reason = "max_iterations";
  for (int it = 0; it < options.max_iterations; ++it) {
    if (grad_norm <= grad_tol) {
      res.stop_reason = "grad_norm";
      break;
    }
    if (paired_met()) {
      res.stop_reason = "preconditioned_grad_norm";
      break;
    }
    if (options.paired_predicted_rel_decrease_tol > 0 &&
        grad_norm <= options.paired_grad_norm_tol &&
        predicted_decrease() <= options.paired_predicted_rel_decrease_tol * std::abs(f)) {
      res.stop_reason = "paired_predicted_decrease";
      break;
    }
    if (options.predicted_rel_decrease_tol > 0 &&
        predicted_decrease() <= options.predicted_rel_decrease_tol * std::abs(f)) {
      res.stop_reason = "predicted_decrease";
      break;
    }
    if (elapsed() > options.max_time_s) {
      res.stop_reason = "time";
      break;
    }
    const double kappa =
        options.tcg_kappa_near > 0 && grad_norm <= options.near_relative_grad * grad_norm0
            ? options.tcg_kappa_near
            : options.tcg_kappa;
    if (reset_radius) {
      // The radius is measured in the preconditioner's norm: after a change of preconditioner
      // it is set again as at the start.
      reset_radius = false;
      ensure_precon_grad();
      radius = std::max(1e-10, options.initial_radius_scale *
                                   std::sqrt(std::max(0.0, frobenius_inner(precon_grad, grad))));
    }
    TcgOutcome step = truncated_cg(problem, M, res.X, egrad, grad, radius, options, preconditioner,
                                   have_precon_grad ? &precon_grad : nullptr, kappa);
    res.total_inner_iterations += step.iterations;
    if (step.preconditioner_changed) {
      // The step is computed again from the same point with the new preconditioner, its
      // gradient and radius set as at the start (taking the truncated step instead cost one
      // more outer step on cubicle and sphere2500). Not counted as an iteration, once a point.
      have_precon_grad = false;
      reset_radius = options.initial_radius <= 0;
      if (!recomputed_here) {
        recomputed_here = true;
        --it;
      }
      continue;
    }
    recomputed_here = false;
    Eigen::MatrixXd X_new =
        options.retraction ? options.retraction(res.X, step.eta) : M.retract(res.X, step.eta);
    if (refine) (*refine)(X_new);
    double f_new_share = 0.0;
    const double f_new = problem.cost(X_new, &f_new_share);
    const double model_decrease =
        -(frobenius_inner(grad, step.eta) + 0.5 * frobenius_inner(step.Heta, step.eta));
    double rho = (f - f_new) / std::max(model_decrease, std::numeric_limits<double>::min());
    // When both decreases sit at round-off level, the ratio is noise: trust the model.
    const bool round_off =
        std::abs(f - f_new) <= 1e-14 * std::abs(f) && model_decrease <= 1e-14 * std::abs(f);
    if (round_off) rho = 1.0;
    if (rho < 0.25) {
      radius *= 0.25;
    } else if (rho > 0.75 && step.hit_boundary) {
      radius = std::min(2.0 * radius, options.max_radius);
    }
    const bool accepted = rho > options.acceptance_ratio && f_new <= f;
    // A step that changes f only at round-off level but happens to raise it: nothing measurable
    // is left to gain, and retrying would repeat the same step with the same radius forever.
    if (!accepted && round_off) {
      res.iterations = it + 1;
      res.stop_reason = "relative_decrease";
      break;
    }
    if (!accepted && rho >= 0.25) radius *= 0.25;  // every rejection shrinks the region
    double decrease = 0.0;
    if (accepted) {
      have_precon_grad = false;  // the gradient changes
      decrease = f - f_new;
      res.X = std::move(X_new);
      f = f_new;
      f_share = f_new_share;
      egrad = problem.euclidean_gradient(res.X);
      grad = M.tangent_project(res.X, egrad);
      grad_norm = std::sqrt(frobenius_inner(grad, grad));
      ++accepted_steps;
    }
    res.iterations = it + 1;
    if (options.record_trace)
      res.trace.push_back({it + 1, f, grad_norm, radius, rho, step.iterations, accepted, elapsed(),
                           options.predicted_rel_decrease_tol > 0
                               ? predicted_decrease()
                               : std::numeric_limits<double>::quiet_NaN()});
    // With the prediction on, a small decrease ends the run only when the prediction agrees:
    // a step can gain little yet leave more to gain than the prediction's tolerance (kitti_00:
    // a step of 6e-7 f left 3.8e-8 f, predicted 5.7e-8 f).
    if (accepted && decrease <= options.rel_cost_decrease_tol * std::abs(f) &&
        (options.predicted_rel_decrease_tol <= 0 ||
         predicted_decrease() <= options.predicted_rel_decrease_tol * std::abs(f))) {
      res.stop_reason = "relative_decrease";
      break;
    }
    if (accepted && options.step_norm_tol > 0 &&
        rotation_norm(step.eta, M.dim()) < options.step_norm_tol) {
      res.stop_reason = "step_norm";
      break;
    }
    if (radius < 1e-14) {
      res.stop_reason = "radius";
      break;
    }
    if (options.max_accepted_steps > 0 && accepted_steps >= options.max_accepted_steps) {
      res.stop_reason = "steps";
      break;
    }
  }
  if (grad_norm <= grad_tol) res.stop_reason = "grad_norm";
  res.cost = f;
  res.cost_share = f_share;
  res.grad_norm = grad_norm;
  return res;
}

}  // namespace tessera
