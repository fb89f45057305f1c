#include <algorithm>
#include <cmath>
#include <tessera/certification/dual_bound.hpp>

namespace tessera {

const char* certificate_method_name(CertificateMethod m) {
  switch (m) {
    case CertificateMethod::kExact:
      return "exact";
    case CertificateMethod::kLobpcg:
      return "lobpcg";
    default:
      return "none";
  }
}

double DualBound::relative_suboptimality(double cost) const {
  return suboptimality(cost) / std::max(1.0, std::abs(relaxation_cost));
}

DualBound make_dual_bound(double relaxation_cost, double trace_lambda, double gradient_norm,
                          double shift_sum, std::size_t poses, int d) {
  DualBound b;
  b.relaxation_cost = relaxation_cost;
  b.trace_lambda = trace_lambda;
  b.gradient_norm = gradient_norm;
  b.method = CertificateMethod::kExact;
  if (std::isfinite(shift_sum) && poses > 0) {
    b.shift = shift_sum / static_cast<double>(poses);
    b.lower_bound = trace_lambda - shift_sum * d;
  }
  return b;
}

double first_proof_shift(double relaxation_cost, std::size_t poses, int d, double tolerance,
                         double scale) {
  const double nd = std::max(1.0, static_cast<double>(poses) * d);
  return std::max(0.1 * tolerance * std::max(1.0, std::abs(relaxation_cost)) / nd,
                  1e-13 * std::max(1.0, scale));
}

double largest_certifying_multiplier(double relaxation_cost, double trace_lambda, double s0,
                                     double weight_sum, std::size_t poses, int d,
                                     double tolerance) {
  const double budget = kCertifyingMargin * tolerance * std::max(1.0, std::abs(relaxation_cost)) -
                        (relaxation_cost - trace_lambda);
  const double per_unit = d * (s0 * static_cast<double>(poses) + weight_sum);
  if (!(budget > 0) || !(per_unit > 0) || !std::isfinite(budget / per_unit)) return 0.0;
  return budget / per_unit;
}

bool bound_certifies(const DualBound& bound, double tolerance) {
  return bound.proved() && bound.relative_suboptimality(bound.relaxation_cost) <= tolerance;
}

std::vector<double> proof_shift_weights(const Eigen::MatrixXd& YS, const SparseMatrix& Q, int d) {
  const Eigen::Index w = d + 1;
  const Eigen::Index m = YS.cols() / w;
  std::vector<double> out(static_cast<std::size_t>(m), 0.0);
  for (Eigen::Index i = 0; i < m; ++i) {
    double k = 0.0;
    for (int c = 0; c < d; ++c) k += Q.coeff(w * i + c, w * i + c);
    k = std::max(k / d, 1e-300);
    out[static_cast<std::size_t>(i)] = YS.middleCols(w * i, w).squaredNorm() / k;
  }
  return out;
}

Eigen::VectorXd proof_shift_diagonal(const std::vector<std::size_t>& poses, int d,
                                     const std::vector<double>& weights, double s0, double alpha) {
  const Eigen::Index w = d + 1;
  Eigen::VectorXd D = Eigen::VectorXd::Zero(w * static_cast<Eigen::Index>(poses.size()));
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Index c = w * static_cast<Eigen::Index>(i);
    D.segment(c, d).setConstant(s0 + alpha * weights[i]);
    if (poses[i] == 0) D(c + d) = s0;
  }
  return D;
}

}  // namespace tessera
