#pragma once
// The pieces of GNC-TLS that act on one measurement: its whitened residual, the chi-square
// default of the inlier bound, mu's starting value and the closed-form weight update
// (Yang, Antonante, Tzoumas, Carlone, "Graduated non-convexity for robust spatial
// perception", RA-L 2020, TLS case). The centralized loop and each agent of the distributed
// one call the same functions, so both sides of a cut measurement compute the same weight.

#include <cstddef>
#include <tessera/graph/measurement.hpp>
#include <tessera/graph/pose.hpp>
#include <tessera/robust/robust_options.hpp>

namespace tessera {

/// The measurement's term of the objective at poses a = x_i, b = x_j:
/// r^2 = kappa ||R_j - R_i R_ij||_F^2 + tau ||t_j - t_i - R_i t_ij||^2.
double residual_squared(const Measurement& m, const Pose& a, const Pose& b);

/// The same term of the relaxed objective at lifted poses Xi, Xj (r x (d+1) each, [Y | p]):
/// kappa ||Y_j - Y_i R_ij||_F^2 + tau ||p_j - p_i - Y_i t_ij||^2 (r^2 above when the rank is d).
double lifted_residual_squared(const Measurement& m, const Eigen::MatrixXd& Xi,
                               const Eigen::MatrixXd& Xj);

/// x with P(chi^2_dof <= x) = p (regularised incomplete gamma, bisection to 1e-12 relative).
/// dof >= 1, p in (0, 1).
double chi_square_quantile(double p, int dof);

/// c^2 of the TLS cost for a d-dimensional problem with `candidates` measurements that may be
/// rejected: inlier_threshold^2 when set, else the chi-square quantile with d(d+1)/2 degrees
/// of freedom at options.inlier_quantile (0: at 1 - 1e-4 / max(1, candidates)).
double tls_threshold_squared(const RobustOptions& options, int d, std::size_t candidates);

/// True when `known` says m can never be an outlier (kOdometry: consecutive pose ids).
bool is_known_inlier(const Measurement& m, KnownInliers known);

/// GNC's first mu = c^2 / (2 max_r2 - c^2), where the surrogate is convex over every
/// residual; 0 when 2 max_r2 <= c^2 (every residual inside the bound: nothing to reject).
double gnc_initial_mu(double max_r2, double c2);

/// The closed-form TLS weight at control parameter mu > 0: 1 when r^2 <= mu/(mu+1) c^2,
/// 0 when r^2 >= (mu+1)/mu c^2, c/r sqrt(mu(mu+1)) - mu in between (continuous in r^2).
double tls_weight(double r2, double c2, double mu);

}  // namespace tessera
