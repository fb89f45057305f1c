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

namespace {

// Fixed-size arithmetic: this runs once per edge, millions of times for the large graphs.
template <int D>
Measurement measure(std::size_t i, std::size_t j, const Pose& from, const Pose& to,
                    const NoiseModel& noise, RandomStream& random) {
  using Rotation = Eigen::Matrix<double, D, D>;
  using Vector = Eigen::Matrix<double, D, 1>;
  constexpr int kRotationDof = D == 2 ? 1 : 3;
  Eigen::Matrix<double, kRotationDof, 1> w;
  for (int k = 0; k < kRotationDof; ++k) w(k) = noise.rotation_sigma * random.normal();
  Vector e;
  for (int k = 0; k < D; ++k) e(k) = noise.translation_sigma * random.normal();

  const Eigen::Map<const Rotation> Ri(from.R.data()), Rj(to.R.data());
  const Eigen::Map<const Vector> ti(from.t.data()), tj(to.t.data());
  Rotation exp_w;
  if constexpr (D == 2)
    exp_w = planar_rotation(w(0));
  else
    exp_w = so3_exp(w);

  Measurement m;
  m.i = i;
  m.j = j;
  m.R = Ri.transpose() * Rj * exp_w;
  m.t = Ri.transpose() * (tj - ti) + e;
  m.kappa = noise.kappa();
  m.tau = noise.tau();
  return m;
}

}  // namespace

Measurement noisy_measurement(std::size_t i, std::size_t j, const Pose& from, const Pose& to,
                              const NoiseModel& noise, RandomStream& random) {
  return from.dim() == 2 ? measure<2>(i, j, from, to, noise, random)
                         : measure<3>(i, j, from, to, noise, random);
}

}  // namespace tessera
