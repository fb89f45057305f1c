#include "distributed/rbcd.hpp"

#include <cmath>

#include "distributed/momentum.hpp"
#include "solvers/trust_region.hpp"
#include "util/input_error.hpp"

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
  if (!(tangent_radius_scale > 0 && std::isfinite(tangent_radius_scale)))
    fail("tangent_radius_scale", "must be finite and > 0");
}

Eigen::MatrixXd block_update(const BlockProblem& problem, const Eigen::MatrixXd& X0,
                             const BlockUpdateOptions& options, BlockPreconditioner* preconditioner,
                             double* grad_norm_sq, const TangentPreconditioner* tangent,
                             BlockUpdateStats* stats) {
  TrustRegionOptions tr;
  tr.max_iterations = 1;
  tr.max_inner_iterations = options.max_inner_iterations;
  tr.tcg_kappa = options.tcg_kappa;
  tr.grad_norm_tol = 0.0;
  tr.rel_cost_decrease_tol = 0.0;
  tr.record_trace = true;
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
  Eigen::MatrixXd X = X0;
  int accepted = 0;
  double radius = 0.0;  // <= 0: set from the first preconditioned gradient
  for (int attempt = 0; attempt < options.max_attempts && accepted < options.trust_region_steps;
       ++attempt) {
    tr.initial_radius = radius;
    TrustRegionResult res = solve_trust_region(problem, X, tr, precon);
    ++local.trust_region_iterations;
    local.tcg_iterations += res.total_inner_iterations;
    // res.grad_norm is at res.X, which is X after this attempt whether or not it is accepted.
    if (grad_norm_sq) *grad_norm_sq = res.grad_norm * res.grad_norm;
    local.cost_share = res.cost_share;
    if (res.trace.empty()) break;  // zero gradient: nothing to do
    const TrustRegionIteration& it = res.trace.back();
    radius = it.radius;
    if (it.accepted) {
      X = std::move(res.X);
      ++accepted;
    }
    if (radius < 1e-14) break;
  }
  if (stats) *stats = local;
  return X;
}

}  // namespace tessera
