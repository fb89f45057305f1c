#include <cmath>
#include <tessera/distributed/momentum.hpp>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/solvers/trust_region.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {

void BlockUpdateOptions::validate() const {
  auto fail = [](const char* field, const char* why) {
    throw InputError(std::string("BlockUpdateOptions.") + field + " " + why);
  };
  if (trust_region_steps < 1) fail("trust_region_steps", "must be >= 1");
  if (max_attempts < trust_region_steps) fail("max_attempts", "must be >= trust_region_steps");
  if (max_inner_iterations < 1) fail("max_inner_iterations", "must be >= 1");
  if (!(tcg_kappa > 0 && tcg_kappa < 1)) fail("tcg_kappa", "must be in (0, 1)");
  if (tangent_refresh_interval < 0) fail("tangent_refresh_interval", "must be >= 0");
  if (!(tangent_relative_shift >= 0 && std::isfinite(tangent_relative_shift)))
    fail("tangent_relative_shift", "must be finite and >= 0");
  if (!(grad_reduction >= 0 && grad_reduction < 1)) fail("grad_reduction", "must be in [0, 1)");
  if (!(tangent_supernodal_min_flops >= 0 && std::isfinite(tangent_supernodal_min_flops)))
    fail("tangent_supernodal_min_flops", "must be finite and >= 0");
  if (!(tangent_radius_scale > 0 && std::isfinite(tangent_radius_scale)))
    fail("tangent_radius_scale", "must be finite and > 0");
}

Eigen::MatrixXd block_update(const BlockProblem& problem, const Eigen::MatrixXd& X0,
                             const BlockUpdateOptions& options, BlockPreconditioner* preconditioner,
                             double* grad_norm_sq, const TangentPreconditioner* tangent,
                             BlockUpdateStats* stats) {
  // One trust-region run: `trust_region_steps` accepted steps within `max_attempts` attempts
  // (a rejected step shrinks the radius and retries from the same point and gradient).
  TrustRegionOptions tr;
  tr.max_iterations = options.max_attempts;
  tr.max_accepted_steps = options.trust_region_steps;
  tr.relative_grad_tol = options.grad_reduction;
  tr.max_inner_iterations = options.max_inner_iterations;
  tr.tcg_kappa = options.tcg_kappa;
  tr.grad_norm_tol = 0.0;
  tr.rel_cost_decrease_tol = 0.0;
  tr.record_trace = false;
  const LiftedManifold M = problem.manifold(static_cast<int>(X0.rows()));
  tr.retraction = [&M](const Eigen::MatrixXd& X, const Eigen::MatrixXd& V) {
    return project_to_manifold(M, X + V);
  };
  const RiemannianPreconditioner* precon = options.precondition ? preconditioner : nullptr;
  BlockUpdateStats local;
  if (options.precondition && tangent) {
    precon = tangent;
    local.tangent = true;
    tr.initial_radius_scale = options.tangent_radius_scale;
  }
  TrustRegionResult res = solve_trust_region(problem, X0, tr, precon);
  local.trust_region_iterations = res.iterations;
  local.tcg_iterations = res.total_inner_iterations;
  // res.grad_norm and res.cost_share are at res.X (X0 when no step was accepted).
  if (grad_norm_sq) *grad_norm_sq = res.grad_norm * res.grad_norm;
  local.cost_share = res.cost_share;
  if (stats) *stats = local;
  return std::move(res.X);
}

}  // namespace tessera
