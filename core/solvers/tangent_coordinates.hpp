#pragma once
// Tangent-coordinate kernels of the tangent preconditioner (tangent_preconditioner.hpp): each
// pose's basis of p = d(d+1)/2 tangent directions, A's p x p blocks from Q's pose blocks, and
// J^T V / J c pose by pose. The fixed-d kernels are templates, here so that callers inline them.

#include <Eigen/Core>
#include <algorithm>
#include <utility>
#include <vector>

#include "solvers/tangent_coordinate_lanes.hpp"

namespace tessera {

// The rotation-coordinate index pairs (a < b) of the skew basis E_ab = e_b e_a^T - e_a e_b^T.
std::vector<std::pair<int, int>> skew_pairs(int d);

// G (d(d+1) x p): the pose's tangent basis vectors, each the column-major vec of a d x (d+1)
// pose block, at rotation Y (d x d).
Eigen::MatrixXd pose_basis(const Eigen::Ref<const Eigen::MatrixXd>& Y,
                           const std::vector<std::pair<int, int>>& pairs);

// Block (i, j) of A, 2 G_i^T (Q_ij kron I_d) G_j (p x p), into B; T (d(d+1) x p) is scratch.
void tangent_block(const Eigen::Ref<const Eigen::MatrixXd>& Qij, const Eigen::MatrixXd& Gi,
                   const Eigen::MatrixXd& Gj, int d, Eigen::MatrixXd& T, Eigen::MatrixXd& B);

// tangent_block for a fixed d (2 or 3), written straight into A's value array (column c of the
// block at out + c * stride): fixed-size products instead of dynamic ones, whose per-call
// dispatch and temporaries made the assembly as costly as the numeric factorization (a block
// that grew is assembled again at every online step). `diagonal` (a diagonal block, i = j):
// the block is made exactly symmetric and its largest diagonal entry returned there.
template <int D>
void tangent_block_fixed(const double* Qij, const Eigen::MatrixXd& Gi, const Eigen::MatrixXd& Gj,
                         double* out, Eigen::Index stride, double* diagonal = nullptr) {
  constexpr int W = D + 1, P = D * (D + 1) / 2;
  const Eigen::Map<const Eigen::Matrix<double, D * W, P>> gi(Gi.data()), gj(Gj.data());
  Eigen::Matrix<double, D * W, P> T;
  for (int t = 0; t < W; ++t) {
    auto row = T.template middleRows<D>(t * D);
    row.setZero();
    for (int u = 0; u < W; ++u) {
      const double q = Qij[u * W + t];
      if (q != 0.0) row.noalias() += q * gj.template middleRows<D>(u * D);
    }
  }
  Eigen::Matrix<double, P, P> B = 2.0 * gi.transpose() * T;
  if (diagonal) {
    B = (0.5 * (B + B.transpose())).eval();  // exactly symmetric
    *diagonal = B.diagonal().maxCoeff();
  }
  for (int c = 0; c < P; ++c) std::copy(B.col(c).data(), B.col(c).data() + P, out + c * stride);
}

// J^T V and J c pose by pose for a fixed d (2 or 3): fixed-size arrays instead of dynamic d x d
// products (whose per-coefficient dispatch was ~40% of an apply on parking-garage). Every dot
// product is summed over k = 0..d-1 in order, as Eigen's lazy products of the previous
// version did, so the result is bit-identical to it.
template <int D>
void tangent_coordinates(const double* X, const double* V, Eigen::Index m, double* b) {
  constexpr int W = D + 1, P = D * (D + 1) / 2, NR = P - D;
  Eigen::Index i = 0;
  if constexpr (D == 3) i = tangent_coordinates_in_lanes(X, V, m, b);  // the same bits
  for (; i < m; ++i) {
    const double* Y = X + i * W * D;   // d x d rotation block, column-major
    const double* Vi = V + i * W * D;  // d x (d+1) pose block
    double Wm[D][W];                   // Wm[a][c] = (Y^T V_i)(a, c)
    for (int c = 0; c < W; ++c)
      for (int a = 0; a < D; ++a) {
        double s = Y[a * D] * Vi[c * D];
        for (int k = 1; k < D; ++k) s += Y[a * D + k] * Vi[c * D + k];
        Wm[a][c] = s;
      }
    double* bi = b + i * P;
    int k = 0;
    for (int a = 0; a < D; ++a)
      for (int bb = a + 1; bb < D; ++bb, ++k) bi[k] = Wm[bb][a] - Wm[a][bb];
    for (int a = 0; a < D; ++a) bi[NR + a] = Wm[a][D];
  }
}

template <int D>
void tangent_vector(const double* X, const double* c, Eigen::Index m, double* Z) {
  constexpr int W = D + 1, P = D * (D + 1) / 2, NR = P - D;
  Eigen::Index i = 0;
  if constexpr (D == 3) i = tangent_vector_in_lanes(X, c, m, Z);  // the same bits
  for (; i < m; ++i) {
    const double* Y = X + i * W * D;
    const double* ci = c + i * P;
    double S[W][D] = {};  // S[col][row]: Omega(omega) and u
    int k = 0;
    for (int a = 0; a < D; ++a)
      for (int bb = a + 1; bb < D; ++bb, ++k) {
        S[a][bb] += ci[k];
        S[bb][a] -= ci[k];
      }
    for (int a = 0; a < D; ++a) S[D][a] = ci[NR + a];
    double* Zi = Z + i * W * D;
    for (int col = 0; col < W; ++col)
      for (int row = 0; row < D; ++row) {
        double s = Y[row] * S[col][0];
        for (int kk = 1; kk < D; ++kk) s += Y[kk * D + row] * S[col][kk];
        Zi[col * D + row] = s;
      }
  }
}

}  // namespace tessera
