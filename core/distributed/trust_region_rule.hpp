#pragma once
// The trust-region rule of the Newton refinement: from the model's predicted decrease and the
// actual one, whether the trial point is taken and the next radius. Pure arithmetic, the same on
// every agent from the same summed numbers.

namespace tessera {

struct TrustRegionVerdict {
  double rho = 0.0;  ///< (actual + reg) / (predicted + reg)
  bool accepted = false;
  double radius = 0.0;  ///< the radius for the next step
};

/// f, f_trial: the cost at the point and at the trial point; `step_norm`: the length of the step
/// taken; `on_boundary`: the CG stopped on the trust region's boundary.
TrustRegionVerdict judge_trust_region_step(double f, double f_trial, double predicted,
                                           double step_norm, double radius, bool on_boundary,
                                           double accept_ratio);

}  // namespace tessera
