#include "distributed/trust_region_rule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tessera {

TrustRegionVerdict judge_trust_region_step(double f, double f_trial, double predicted,
                                           double step_norm, double radius, bool on_boundary,
                                           double accept_ratio) {
  TrustRegionVerdict v;
  // Ratio with Manopt's regularisation: near the optimum both decreases approach round-off.
  const double reg = std::max(1.0, std::abs(f)) * std::numeric_limits<double>::epsilon() * 1e3;
  v.rho = (f - f_trial + reg) / (predicted + reg);
  // A model that does not decrease says nothing of the step (as Manopt's model_decreased):
  // the ratio of two increases is positive. The refinement's steps with the gauge part taken
  // off (gauge_space.hpp) are not the CG's own, so their model can rise.
  const bool model_decreased = predicted + reg >= 0;
  v.accepted = model_decreased && v.rho > accept_ratio && std::isfinite(f_trial);
  v.radius = radius;
  if (!model_decreased || v.rho < 0.25 || !std::isfinite(f_trial))
    v.radius = 0.25 * step_norm;
  else if (v.rho > 0.75 && radius > 0 && on_boundary)
    v.radius = 2.0 * radius;
  return v;
}

}  // namespace tessera
