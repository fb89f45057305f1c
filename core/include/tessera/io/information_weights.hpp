#pragma once
// Scalar measurement weights from a g2o information matrix, exactly in the convention of
// SE-Sync and the reference optima (../shared/reference/README.md):
//   2D: tau = 2 / trace(inv(T)), kappa = I33            (T = 2x2 translation block)
//   3D: tau = 3 / trace(inv(T)), kappa = 3 / (2 trace(inv(W)))
//       (T = top-left 3x3 translation block, W = bottom-right 3x3 rotation block)
// The translation-rotation cross block is ignored. The formulas are applied as they are,
// even when the full matrix is not positive definite; the caller decides what to do with
// a weight that is not finite and > 0.

#include <array>

namespace tessera {

/// Number of values in a g2o row-major upper triangle: 6 in 2D (3x3), 21 in 3D (6x6).
constexpr int information_upper_size(int d) {
  return d == 2 ? 6 : 21;
}

struct IsotropicWeights {
  double kappa = 0.0;  ///< Rotation weight.
  double tau = 0.0;    ///< Translation weight.

  /// True when both weights are finite and strictly positive (usable in the objective).
  bool valid() const;
};

/// Weights of a 2D information matrix given as its row-major upper triangle
/// (I11 I12 I13 I22 I23 I33; indices 1,2 = x,y and 3 = theta). Never throws: a singular
/// translation block gives tau = 0 or a non-finite value (see IsotropicWeights::valid()).
IsotropicWeights isotropic_weights_2d(const double* upper6);

/// Weights of a 3D information matrix given as its row-major upper triangle (21 values;
/// indices 1-3 = translation, 4-6 = rotation), as in EDGE_SE3:QUAT. Never throws.
IsotropicWeights isotropic_weights_3d(const double* upper21);

/// Whether the symmetric matrix with this row-major upper triangle (size 3 for 2D, 6 for
/// 3D) is positive definite: every Cholesky pivot is finite and > 0.
bool upper_triangle_is_positive_definite(const double* upper, int size);

/// A g2o upper triangle whose weights are exactly (kappa, tau): diag(tau, tau, kappa) in
/// 2D, diag(tau I3, 2 kappa I3) in 3D (other entries 0). Writers use it so that reading
/// their output gives back the same weights. Unused trailing entries of the array are 0.
std::array<double, 21> information_from_weights(int d, double kappa, double tau);

}  // namespace tessera
