#include "robust/gnc_outer_loop.hpp"

#include <algorithm>
#include <tessera/robust/tls_weights.hpp>

namespace tessera {

void GncOuterLoop::start(double largest_residual_squared, double c2, const RobustOptions& options) {
  started_ = true;
  mu_ = gnc_initial_mu(largest_residual_squared, c2);
  factor_ = options.mu_step;
  converged_ = mu_ == 0;
}

bool GncOuterLoop::after_update(double spread, int crossed, int near_bound,
                                const RobustOptions& options, bool newton) {
  ++outer_;
  converged_ = spread <= options.weight_tolerance;
  // RobustOptions::jump_band: every residual clear of the bound, so GNC ends at TLS's verdict at
  // this iterate (the same on both ends of every cut measurement) and the passes follow.
  if (!converged_ && options.jump_band > 0 && near_bound == 0) {
    converged_ = true;
    return true;
  }
  // RobustOptions::mu_step_max (newton_mu_step_max on Newton steps): a bigger step while the
  // inlier set stays as it was, never below mu_step.
  const double step_max = options.mu_step_max > 0 ? options.mu_step_max
                          : newton                ? options.newton_mu_step_max
                                                  : 0.0;
  factor_ = step_max > 0 && crossed == 0
                ? std::max(options.mu_step, std::min(factor_ * factor_, step_max))
                : options.mu_step;
  mu_ *= factor_;
  return false;
}

}  // namespace tessera
