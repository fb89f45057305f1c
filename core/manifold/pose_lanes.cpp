#include "manifold/pose_lanes.hpp"

#include <emmintrin.h>

#include "util/avx_kernels.hpp"
#include "util/lanes.hpp"

namespace tessera {
namespace {

// The group's 3 x 3 rotation blocks at rank R: m[k][i] = entry (i, k).
template <typename V, int L, int R>
TESSERA_LANE_INLINE void gather_rotations(V (&m)[3][3], const double* p) {
#pragma GCC unroll 4
  for (int k = 0; k < 3; ++k)
#pragma GCC unroll 4
    for (int i = 0; i < 3; ++i) gather_lanes<V, L>(m[k][i], p, 4 * R, k * R + i);
}

// sym_product<3, 3>: S = sym(A^T B), each entry of A^T B summed from +0 over k in order.
template <typename V>
TESSERA_LANE_INLINE void sym_product(const V (&a)[3][3], const V (&b)[3][3], V (&s)[3][3]) {
  V p[3][3];
#pragma GCC unroll 4
  for (int x = 0; x < 3; ++x)
#pragma GCC unroll 4
    for (int y = 0; y < 3; ++y) {
      V acc = V{} + 0.0;
      acc += a[x][0] * b[y][0];
      acc += a[x][1] * b[y][1];
      acc += a[x][2] * b[y][2];
      p[x][y] = acc;
    }
    // 0.5 (P + P^T) is symmetric to the bit (the sum commutes).
#pragma GCC unroll 4
  for (int x = 0; x < 3; ++x)
#pragma GCC unroll 4
    for (int y = x; y < 3; ++y) s[x][y] = s[y][x] = 0.5 * (p[x][y] + p[y][x]);
}

// P = A E for the symmetric powers of E: the upper triangle, each entry summed over k in
// order, mirrored (A and E are powers of one symmetric E, so they commute and P is symmetric).
template <typename V>
TESSERA_LANE_INLINE void power_step(const V (&a)[3][3], const V (&e)[3][3], V (&p)[3][3]) {
#pragma GCC unroll 4
  for (int i = 0; i < 3; ++i)
#pragma GCC unroll 4
    for (int j = i; j < 3; ++j) {
      V s = a[i][0] * e[0][j];
      s += a[i][1] * e[1][j];
      s += a[i][2] * e[2][j];
      p[i][j] = p[j][i] = s;
    }
}

// momentum.cpp's project_pose<3, R> for the poses of the series' reach. R = 5: rows 3 and 4
// zero (gram_entry_zero_tail<3>'s order); R = 3: gram_entry<3>'s order.
template <typename V, int L, int R>
TESSERA_LANE_INLINE bool polar(double* A) {
  V a[3][3];
  gather_rotations<V, L, R>(a, A);
  const V zero = V{} + 0.0, one = zero + 1.0;
  // Gram matrix B = A^T A (symmetric: its upper triangle, mirrored), then E = I - B.
  V e1[3][3];
#pragma GCC unroll 4
  for (int p = 0; p < 3; ++p)
#pragma GCC unroll 4
    for (int q = p; q < 3; ++q) {
      const V* x = a[p];
      const V* y = a[q];
      const V b = R == 5 ? (x[0] * y[0] + x[2] * y[2]) + x[1] * y[1]
                         : (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2];
      e1[p][q] = e1[q][p] = (p == q ? one : zero) - b;
    }
  // ||E||_F in frobenius_norm_3's order; the square roots two lanes at a time (SSE2's,
  // correctly rounded as std::sqrt: a library call here would spill every live vector).
  const V n2 =
      ((e1[0][0] * e1[0][0] + e1[2][0] * e1[2][0]) + (e1[1][1] * e1[1][1] + e1[0][2] * e1[0][2])) +
      ((e1[1][0] * e1[1][0] + e1[0][1] * e1[0][1]) + (e1[2][1] * e1[2][1] + e1[1][2] * e1[1][2])) +
      e1[2][2] * e1[2][2];
  V e;
#pragma GCC unroll 2
  for (int l = 0; l < L; l += 2) {
    const __m128d root = _mm_sqrt_pd(__m128d{n2[l], n2[l + 1]});
    e[l] = root[0];
    e[l + 1] = root[1];
  }
#pragma GCC unroll 4
  for (int l = 0; l < L; ++l)
    if (!(e[l] < 1e-4)) return false;  // Newton-Schulz or farther: pose by pose
  // Below 1e-9 the series' first term I + E/2, else I + E/2 + 3E^2/8 + 5E^3/16 (symmetric
  // powers: upper triangles, mirrored), each entry as inv_sqrt_near_identity<3> forms it.
  const auto tiny = e < 1e-9;
  V e2[3][3], e3[3][3], z[3][3];
  power_step(e1, e1, e2);
  power_step(e2, e1, e3);
#pragma GCC unroll 4
  for (int i = 0; i < 3; ++i)
#pragma GCC unroll 4
    for (int j = i; j < 3; ++j) {
      const V id = i == j ? one : zero;
      const V first = id + 0.5 * e1[i][j];
      const V series = id + (0.5 * e1[i][j] + (0.375 * e2[i][j] + 0.3125 * e3[i][j]));
      z[i][j] = z[j][i] = tiny ? first : series;
    }
    // A Z, each entry summed over k in order.
#pragma GCC unroll 4
  for (int j = 0; j < 3; ++j)
#pragma GCC unroll 4
    for (int i = 0; i < 3; ++i) {
      V s = a[0][i] * z[0][j];
      s += a[1][i] * z[1][j];
      s += a[2][i] * z[2][j];
      scatter_lanes<V, L>(s, A, 4 * R, j * R + i);
    }
  return true;
}

// tangent_project_poses<3, 3>: out = V - X sym(X^T V), column b of each pose as
// ((v + w_0b x_0) + w_1b x_1) + w_2b x_2 with w = -1 * sym.
template <typename V, int L>
TESSERA_LANE_INLINE void tangent_project(const double* X, const double* Vp, double* out) {
  V x[3][3], v[3][3], s[3][3];
  gather_rotations<V, L, 3>(x, X);
  gather_rotations<V, L, 3>(v, Vp);
  sym_product(x, v, s);
#pragma GCC unroll 4
  for (int b = 0; b < 3; ++b)
#pragma GCC unroll 4
    for (int k = 0; k < 3; ++k) {
      V o = v[b][k] + (-1.0 * s[0][b]) * x[0][k];
      o = o + (-1.0 * s[1][b]) * x[1][k];
      o = o + (-1.0 * s[2][b]) * x[2][k];
      scatter_lanes<V, L>(o, out, 12, 3 * b + k);
    }
}

// hessian_projection<3, 3>: column b of each pose's H minus, for a = 0, 1, 2 in order,
// sym(X^T H)_ab x_a + sym(X^T G)_ab v_a.
template <typename V, int L>
TESSERA_LANE_INLINE void hessian_projection(const double* X, const double* G, const double* Vp,
                                            double* H) {
  V x[3][3], h[3][3], sh[3][3], sg[3][3];
  gather_rotations<V, L, 3>(x, X);
  gather_rotations<V, L, 3>(h, H);
  sym_product(x, h, sh);
  {
    V g[3][3];
    gather_rotations<V, L, 3>(g, G);
    sym_product(x, g, sg);
  }
  V v[3][3];
  gather_rotations<V, L, 3>(v, Vp);
#pragma GCC unroll 4
  for (int b = 0; b < 3; ++b)
#pragma GCC unroll 4
    for (int k = 0; k < 3; ++k) {
      V o = h[b][k];
#pragma GCC unroll 4
      for (int a = 0; a < 3; ++a) o -= sh[a][b] * x[a][k] + sg[a][b] * v[a][k];
      scatter_lanes<V, L>(o, H, 12, 3 * b + k);
    }
}

bool polar_sse2(double* A, Eigen::Index r) {
  return r == 5 ? polar<Lanes2, 2, 5>(A) : polar<Lanes2, 2, 3>(A);
}

void tangent_project_sse2(const double* X, const double* V, double* out) {
  tangent_project<Lanes2, 2>(X, V, out);
}

void hessian_projection_sse2(const double* X, const double* G, const double* V, double* H) {
  hessian_projection<Lanes2, 2>(X, G, V, H);
}

#ifdef TESSERA_AVX_KERNELS
__attribute__((target("avx"))) bool polar_avx(double* A, Eigen::Index r) {
  return r == 5 ? polar<Lanes4, 4, 5>(A) : polar<Lanes4, 4, 3>(A);
}

__attribute__((target("avx"))) void tangent_project_avx(const double* X, const double* V,
                                                        double* out) {
  tangent_project<Lanes4, 4>(X, V, out);
}

__attribute__((target("avx"))) void hessian_projection_avx(const double* X, const double* G,
                                                           const double* V, double* H) {
  hessian_projection<Lanes4, 4>(X, G, V, H);
}
#endif

}  // namespace

int pose_lanes() {
#ifdef TESSERA_AVX_KERNELS
  if (avx_kernels_enabled()) return 4;
#endif
  return 2;
}

bool polar_in_lanes(double* A, int lanes, Eigen::Index r) {
#ifdef TESSERA_AVX_KERNELS
  if (lanes == 4) return polar_avx(A, r);
#endif
  (void)lanes;
  return polar_sse2(A, r);
}

void tangent_project_in_lanes(const double* X, const double* V, int lanes, double* out) {
#ifdef TESSERA_AVX_KERNELS
  if (lanes == 4) return tangent_project_avx(X, V, out);
#endif
  (void)lanes;
  tangent_project_sse2(X, V, out);
}

void hessian_projection_in_lanes(const double* X, const double* G, const double* V, int lanes,
                                 double* H) {
#ifdef TESSERA_AVX_KERNELS
  if (lanes == 4) return hessian_projection_avx(X, G, V, H);
#endif
  (void)lanes;
  hessian_projection_sse2(X, G, V, H);
}

}  // namespace tessera
