#include <cmath>
#include <tessera/io/information_weights.hpp>
#include <utility>

namespace tessera {
namespace {

// Element (r, c) of the symmetric matrix of size n stored as a row-major upper triangle.
double upper_at(const double* upper, int n, int r, int c) {
  if (r > c) std::swap(r, c);
  // Rows before r hold n + (n-1) + ... + (n-r+1) values.
  const int row_start = r * n - r * (r - 1) / 2;
  return upper[row_start + (c - r)];
}

// trace(inv(A)) for the symmetric 3x3 block A starting at (k, k): the sum of the principal
// 2x2 minors divided by the determinant (cofactor form of the inverse's diagonal).
double trace_of_inverse_3x3(const double* upper, int n, int k) {
  auto a = [&](int r, int c) { return upper_at(upper, n, k + r, k + c); };
  const double m00 = a(1, 1) * a(2, 2) - a(1, 2) * a(1, 2);
  const double m11 = a(0, 0) * a(2, 2) - a(0, 2) * a(0, 2);
  const double m22 = a(0, 0) * a(1, 1) - a(0, 1) * a(0, 1);
  const double det = a(0, 0) * m00 - a(0, 1) * (a(0, 1) * a(2, 2) - a(1, 2) * a(0, 2)) +
                     a(0, 2) * (a(0, 1) * a(1, 2) - a(1, 1) * a(0, 2));
  return (m00 + m11 + m22) / det;
}

}  // namespace

bool IsotropicWeights::valid() const {
  return std::isfinite(kappa) && std::isfinite(tau) && kappa > 0.0 && tau > 0.0;
}

IsotropicWeights isotropic_weights_2d(const double* upper6) {
  const double a = upper6[0], b = upper6[1], c = upper6[3];
  const double trace_inv = (a + c) / (a * c - b * b);
  return {upper6[5], 2.0 / trace_inv};
}

IsotropicWeights isotropic_weights_3d(const double* upper21) {
  const double tau = 3.0 / trace_of_inverse_3x3(upper21, 6, 0);
  const double kappa = 3.0 / (2.0 * trace_of_inverse_3x3(upper21, 6, 3));
  return {kappa, tau};
}

bool upper_triangle_is_positive_definite(const double* upper, int size) {
  // Cholesky on the lower triangle of a small dense copy (size 3 or 6); stops at the first
  // pivot that is not > 0. Runs once per edge, so it unpacks sequentially.
  double l[6][6];
  for (int r = 0, k = 0; r < size; ++r)
    for (int c = r; c < size; ++c) l[c][r] = upper[k++];
  for (int k = 0; k < size; ++k) {
    double pivot = l[k][k];
    for (int m = 0; m < k; ++m) pivot -= l[k][m] * l[k][m];
    if (!(pivot > 0.0) || !std::isfinite(pivot)) return false;
    const double root = std::sqrt(pivot);
    l[k][k] = root;
    for (int r = k + 1; r < size; ++r) {
      double v = l[r][k];
      for (int m = 0; m < k; ++m) v -= l[r][m] * l[k][m];
      l[r][k] = v / root;
    }
  }
  return true;
}

std::array<double, 21> information_from_weights(int d, double kappa, double tau) {
  std::array<double, 21> upper{};
  if (d == 2) {
    upper[0] = tau;    // I11
    upper[3] = tau;    // I22
    upper[5] = kappa;  // I33
  } else {
    // Diagonal positions of a 6x6 row-major upper triangle: 0, 6, 11, 15, 18, 20.
    const int diag[6] = {0, 6, 11, 15, 18, 20};
    for (int k = 0; k < 3; ++k) upper[diag[k]] = tau;
    for (int k = 3; k < 6; ++k) upper[diag[k]] = 2.0 * kappa;
  }
  return upper;
}

}  // namespace tessera
