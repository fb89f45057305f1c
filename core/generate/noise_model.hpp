#pragma once
// Measurement noise of the generator and the weights that match it.

#include <cstddef>
#include <tessera/graph/measurement.hpp>
#include <tessera/graph/pose.hpp>

#include "generate/random_stream.hpp"

namespace tessera {

/// Isotropic noise: R_ij = R_i^T R_j Exp(w), w ~ N(0, rotation_sigma^2 I) (1 entry in 2D,
/// 3 in 3D); t_ij = R_i^T (t_j - t_i) + e, e ~ N(0, translation_sigma^2 I_d).
struct NoiseModel {
  double rotation_sigma = 0.0;     ///< rad, >= 0
  double translation_sigma = 0.0;  ///< m, >= 0

  /// Rotation weight kappa = 1 / (2 sigma_R^2): to second order in w,
  /// kappa ||R_j - R_i R_ij||_F^2 = |w|^2 / sigma_R^2, so the objective is twice the
  /// negative log-likelihood (the isotropic Langevin model of SE-Sync). sigma_R is floored
  /// at kMinSigma so that a noise-free graph keeps finite weights.
  double kappa() const;
  /// Translation weight tau = 1 / sigma_t^2 (sigma_t floored at kMinSigma likewise).
  double tau() const;

  static constexpr double kMinSigma = 1e-3;
};

/// The measurement of `to` seen from `from` (ids i -> j), with noise drawn from `random`
/// and the model's weights. Always draws d(d-1)/2 + d normals (rotation first), even for
/// zero noise, so the noise of every edge depends only on the seed and the edge's position.
Measurement noisy_measurement(std::size_t i, std::size_t j, const Pose& from, const Pose& to,
                              const NoiseModel& noise, RandomStream& random);

}  // namespace tessera
