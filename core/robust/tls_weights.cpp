#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tessera/robust/tls_weights.hpp>

namespace tessera {
namespace {

// P(a, x), the regularised lower incomplete gamma function: the series for x < a + 1, the
// continued fraction (Lentz) otherwise; both converge fast in their ranges.
double lower_gamma_regularised(double a, double x) {
  if (x <= 0) return 0.0;
  const double log_prefix = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000 && std::abs(term) > 1e-16 * std::abs(sum); ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return sum * std::exp(log_prefix);
  }
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, dd = 1 / b, h = dd;
  for (int n = 1; n < 1000; ++n) {
    const double an = -n * (n - a);
    b += 2;
    dd = an * dd + b;
    if (std::abs(dd) < tiny) dd = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    dd = 1 / dd;
    const double step = dd * c;
    h *= step;
    if (std::abs(step - 1) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefix) * h;
}

}  // namespace

double residual_squared(const Measurement& m, const Pose& a, const Pose& b) {
  return m.kappa * (b.R - a.R * m.R).squaredNorm() + m.tau * (b.t - a.t - a.R * m.t).squaredNorm();
}

double lifted_residual_squared(const Measurement& m, const Eigen::MatrixXd& Xi,
                               const Eigen::MatrixXd& Xj) {
  const Eigen::Index d = m.t.size();
  const auto Yi = Xi.leftCols(d);
  return m.kappa * (Xj.leftCols(d) - Yi * m.R).squaredNorm() +
         m.tau * (Xj.col(d) - Xi.col(d) - Yi * m.t).squaredNorm();
}

double chi_square_quantile(double p, int dof) {
  if (dof < 1 || !(p > 0 && p < 1))
    throw std::invalid_argument("chi_square_quantile: dof >= 1 and p in (0, 1) expected");
  const double k = 0.5 * dof;
  double lo = 0, hi = 1;
  while (lower_gamma_regularised(k, 0.5 * hi) < p) hi *= 2;
  while (hi - lo > 1e-12 * hi) {
    const double mid = 0.5 * (lo + hi);
    (lower_gamma_regularised(k, 0.5 * mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double tls_threshold_squared(const RobustOptions& options, int d, std::size_t candidates) {
  if (options.inlier_threshold > 0) return options.inlier_threshold * options.inlier_threshold;
  const double p = options.inlier_quantile > 0
                       ? options.inlier_quantile
                       : 1.0 - 1e-4 / static_cast<double>(std::max<std::size_t>(1, candidates));
  return chi_square_quantile(p, d * (d + 1) / 2);
}

bool is_known_inlier(const Measurement& m, KnownInliers known) {
  return known == KnownInliers::kOdometry && (m.j == m.i + 1 || m.i == m.j + 1);
}

double gnc_initial_mu(double max_r2, double c2) {
  return 2 * max_r2 <= c2 ? 0.0 : c2 / (2 * max_r2 - c2);
}

double tls_weight(double r2, double c2, double mu) {
  if (r2 <= mu / (mu + 1) * c2) return 1.0;
  if (r2 >= (mu + 1) / mu * c2) return 0.0;
  return std::sqrt(c2 / r2) * std::sqrt(mu * (mu + 1)) - mu;
}

}  // namespace tessera
