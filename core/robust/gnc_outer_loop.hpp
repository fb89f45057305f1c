#pragma once
// GNC-TLS's outer loop on one agent: the control parameter mu, its step, the outer-step count
// and the stop decision. Every agent feeds it the team's sums from the same exchanges, so every
// agent takes the same decisions; the state machine (gnc_agent.cpp) only asks what comes next.

#include <tessera/robust/robust_options.hpp>

namespace tessera {

class GncOuterLoop {
 public:
  /// mu's start from the largest residual^2 any agent may reject and the bound c^2
  /// (gnc_initial_mu); mu = 0 means no measurement can be an outlier: converged at once.
  void start(double largest_residual_squared, double c2, const RobustOptions& options);

  /// After a weight update with the team's weight spread, count of weights that crossed 1/2
  /// (that fell below it, with RobustOptions::mu_step_hold kFalls)
  /// and count of residuals within RobustOptions::jump_band of the bound. Returns true when
  /// GNC ends at TLS's verdict now (the jump: nothing is near the bound); mu stays where it was
  /// for that verdict. Otherwise mu takes its next step (RobustOptions::mu_step, squared up to
  /// mu_step_max while no weight crossed 1/2) and converged() says whether the next solve is
  /// the last weighted one.
  /// `newton`: every weighted solve so far was a Newton step (RobustOptions::newton_mu_step_max
  /// then caps the step while mu_step_max is 0).
  bool after_update(double spread, int crossed, int near_bound, const RobustOptions& options,
                    bool newton = false);

  /// The weighted solves are over: converged, or RobustOptions::max_outer_iterations reached.
  bool over(const RobustOptions& options) const {
    return converged_ || outer_ >= options.max_outer_iterations;
  }
  bool started() const { return started_; }
  double mu() const { return mu_; }
  int outer() const { return outer_; }
  bool converged() const { return converged_; }

 private:
  bool started_ = false;  // the votes of mu's start are in
  double mu_ = 0;
  double factor_ = 1;  // the last step of mu (RobustOptions::mu_step_max)
  int outer_ = 0;
  bool converged_ = false;
};

}  // namespace tessera
