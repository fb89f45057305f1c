#include "solvers/tangent_coordinate_lanes.hpp"

#include "manifold/pose_lanes.hpp"
#include "util/avx_kernels.hpp"
#include "util/lanes.hpp"

namespace tessera {
namespace {

// tangent_coordinates<3>, lane by lane: W = Y^T V_i (each entry summed over k in order), then
// omega_ab = W(b, a) - W(a, b) for (a, b) = (0, 1), (0, 2), (1, 2) and u = W(:, 3).
template <typename V, int L>
TESSERA_LANE_INLINE Eigen::Index coordinates(const double* X, const double* Vp, Eigen::Index m,
                                             double* b) {
  Eigen::Index i = 0;
  for (; i + L <= m; i += L) {
    const double* Y = X + 12 * i;
    const double* Vi = Vp + 12 * i;
    V y[9], wm[3][4];
#pragma GCC unroll 9
    for (int e = 0; e < 9; ++e) gather_lanes<V, L>(y[e], Y, 12, e);
#pragma GCC unroll 4
    for (int c = 0; c < 4; ++c) {
      V v0, v1, v2;
      gather_lanes<V, L>(v0, Vi, 12, 3 * c);
      gather_lanes<V, L>(v1, Vi, 12, 3 * c + 1);
      gather_lanes<V, L>(v2, Vi, 12, 3 * c + 2);
#pragma GCC unroll 3
      for (int a = 0; a < 3; ++a) {
        V s = y[3 * a] * v0;
        s += y[3 * a + 1] * v1;
        s += y[3 * a + 2] * v2;
        wm[a][c] = s;
      }
    }
    double* bi = b + 6 * i;
    scatter_lanes<V, L>(wm[1][0] - wm[0][1], bi, 6, 0);
    scatter_lanes<V, L>(wm[2][0] - wm[0][2], bi, 6, 1);
    scatter_lanes<V, L>(wm[2][1] - wm[1][2], bi, 6, 2);
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) scatter_lanes<V, L>(wm[a][3], bi, 6, 3 + a);
  }
  return i;
}

// tangent_vector<3>, lane by lane: S = [Omega(omega) u] with Omega's entries formed from +0 as
// there (S[a][b] += c_k, S[b][a] -= c_k; the diagonal +0), then Z_i = Y S, each entry summed
// over k in order (the products by the zero entries included).
template <typename V, int L>
TESSERA_LANE_INLINE Eigen::Index vectors(const double* X, const double* c, Eigen::Index m,
                                         double* Z) {
  Eigen::Index i = 0;
  for (; i + L <= m; i += L) {
    const double* Y = X + 12 * i;
    const double* ci = c + 6 * i;
    V y[9], s[4][3];
#pragma GCC unroll 9
    for (int e = 0; e < 9; ++e) gather_lanes<V, L>(y[e], Y, 12, e);
    const V zero = V{} + 0.0;
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) s[a][a] = zero;
    int k = 0;
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a)
#pragma GCC unroll 3
      for (int bb = a + 1; bb < 3; ++bb, ++k) {
        V ck;
        gather_lanes<V, L>(ck, ci, 6, k);
        s[a][bb] = zero + ck;
        s[bb][a] = zero - ck;
      }
#pragma GCC unroll 3
    for (int a = 0; a < 3; ++a) gather_lanes<V, L>(s[3][a], ci, 6, 3 + a);
    double* Zi = Z + 12 * i;
#pragma GCC unroll 4
    for (int col = 0; col < 4; ++col)
#pragma GCC unroll 3
      for (int row = 0; row < 3; ++row) {
        V t = y[row] * s[col][0];
        t += y[3 + row] * s[col][1];
        t += y[6 + row] * s[col][2];
        scatter_lanes<V, L>(t, Zi, 12, 3 * col + row);
      }
  }
  return i;
}

#ifdef TESSERA_AVX_KERNELS
__attribute__((target("avx"))) Eigen::Index coordinates_avx(const double* X, const double* V,
                                                            Eigen::Index m, double* b) {
  return coordinates<Lanes4, 4>(X, V, m, b);
}

__attribute__((target("avx"))) Eigen::Index vectors_avx(const double* X, const double* c,
                                                        Eigen::Index m, double* Z) {
  return vectors<Lanes4, 4>(X, c, m, Z);
}
#endif

}  // namespace

Eigen::Index tangent_coordinates_in_lanes(const double* X, const double* V, Eigen::Index m,
                                          double* b) {
#ifdef TESSERA_AVX_KERNELS
  if (pose_lanes() == 4) return coordinates_avx(X, V, m, b);
#endif
  return coordinates<Lanes2, 2>(X, V, m, b);
}

Eigen::Index tangent_vector_in_lanes(const double* X, const double* c, Eigen::Index m, double* Z) {
#ifdef TESSERA_AVX_KERNELS
  if (pose_lanes() == 4) return vectors_avx(X, c, m, Z);
#endif
  return vectors<Lanes2, 2>(X, c, m, Z);
}

}  // namespace tessera
