#include "generate/noise_model.hpp"

#include <algorithm>

#include "generate/geometry.hpp"

namespace tessera {

double NoiseModel::kappa() const {
  // (1/s)^2 rather than 1/s^2: round noise values then give round weights (0.05 -> 400).
  const double inv = 1.0 / std::max(rotation_sigma, kMinSigma);
  return 0.5 * inv * inv;
}

double NoiseModel::tau() const {
  const double inv = 1.0 / std::max(translation_sigma, kMinSigma);
  return inv * inv;
}

Measurement noisy_measurement(std::size_t i, std::size_t j, const Pose& from, const Pose& to,
                              const NoiseModel& noise, RandomStream& random) {
  const int d = from.dim();
  Eigen::VectorXd w(d == 2 ? 1 : 3);
  for (Eigen::Index k = 0; k < w.size(); ++k) w(k) = noise.rotation_sigma * random.normal();
  Eigen::VectorXd e(d);
  for (int k = 0; k < d; ++k) e(k) = noise.translation_sigma * random.normal();

  Measurement m;
  m.i = i;
  m.j = j;
  m.R = from.R.transpose() * to.R * rotation_exp(w);
  m.t = from.R.transpose() * (to.t - from.t) + e;
  m.kappa = noise.kappa();
  m.tau = noise.tau();
  return m;
}

}  // namespace tessera
