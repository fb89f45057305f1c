#include "manifold/polar_lanes.hpp"

#include <emmintrin.h>

#include "util/avx_kernels.hpp"

namespace tessera {
namespace {

// GCC's vector extension: element-wise operations, each lane rounded as the scalar operation
// (no FMA is ever formed: neither copy is compiled with it).
typedef double Lanes2 __attribute__((vector_size(16)));
typedef double Lanes4 __attribute__((vector_size(32)));

// The kernel is written once and inlined into each copy, where it is compiled for that copy's
// instruction set. Vectors pass by reference only (a 32-byte vector by value would change the
// calling convention of a non-AVX function).
#define TESSERA_LANE_INLINE inline __attribute__((always_inline))

template <typename V, int L>
TESSERA_LANE_INLINE void gather(V& v, double* const* A, Eigen::Index at) {
  if constexpr (L == 4)
    v = V{A[0][at], A[1][at], A[2][at], A[3][at]};
  else
    v = V{A[0][at], A[1][at]};
}

template <typename V, int L>
TESSERA_LANE_INLINE void scatter(const V& v, double* const* A, Eigen::Index at) {
#pragma GCC unroll 4
  for (int l = 0; l < L; ++l) A[l][at] = v[l];
}

// momentum.cpp's project_pose<3, R> for the poses of the series' reach, lane by lane. ZeroTail:
// R = 5 with rows 3 and 4 zero (gram_entry_zero_tail<3>'s order), otherwise R = 3
// (gram_entry<3>'s order).
template <typename V, int L, bool ZeroTail>
TESSERA_LANE_INLINE bool polar(double* const* A, Eigen::Index r) {
  V a[3][3];  // a[k][i]: entry (i, k) of each lane's block
#pragma GCC unroll 4
  for (int k = 0; k < 3; ++k)
#pragma GCC unroll 4
    for (int i = 0; i < 3; ++i) gather<V, L>(a[k][i], A, k * r + i);
  const V zero = {}, one = zero + 1.0;
  // Gram matrix B = A^T A (symmetric: its upper triangle, mirrored), then E = I - B.
  V e1[3][3];
#pragma GCC unroll 4
  for (int p = 0; p < 3; ++p)
#pragma GCC unroll 4
    for (int q = p; q < 3; ++q) {
      const V* x = a[p];
      const V* y = a[q];
      const V b = ZeroTail ? (x[0] * y[0] + x[2] * y[2]) + x[1] * y[1]
                           : (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2];
      e1[p][q] = e1[q][p] = (p == q ? one : zero) - b;
    }
  // ||E||_F in frobenius_norm_3's order.
  const V n2 =
      ((e1[0][0] * e1[0][0] + e1[2][0] * e1[2][0]) + (e1[1][1] * e1[1][1] + e1[0][2] * e1[0][2])) +
      ((e1[1][0] * e1[1][0] + e1[0][1] * e1[0][1]) + (e1[2][1] * e1[2][1] + e1[1][2] * e1[1][2])) +
      e1[2][2] * e1[2][2];
  // The square roots two lanes at a time (SSE2's, correctly rounded as std::sqrt): a library
  // call here would make the compiler spill every live vector around it.
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
#pragma GCC unroll 4
  for (int i = 0; i < 3; ++i)
#pragma GCC unroll 4
    for (int j = i; j < 3; ++j) {
      V s = e1[i][0] * e1[0][j];
      s += e1[i][1] * e1[1][j];
      s += e1[i][2] * e1[2][j];
      e2[i][j] = e2[j][i] = s;
    }
#pragma GCC unroll 4
  for (int i = 0; i < 3; ++i)
#pragma GCC unroll 4
    for (int j = i; j < 3; ++j) {
      V s = e2[i][0] * e1[0][j];
      s += e2[i][1] * e1[1][j];
      s += e2[i][2] * e1[2][j];
      e3[i][j] = e3[j][i] = s;
    }
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
      scatter<V, L>(s, A, j * r + i);
    }
  return true;
}

bool polar_sse2(double* const* A, Eigen::Index r, bool zero_tail) {
  return zero_tail ? polar<Lanes2, 2, true>(A, r) : polar<Lanes2, 2, false>(A, r);
}

#ifdef TESSERA_AVX_KERNELS
__attribute__((target("avx"))) bool polar_avx(double* const* A, Eigen::Index r, bool zero_tail) {
  return zero_tail ? polar<Lanes4, 4, true>(A, r) : polar<Lanes4, 4, false>(A, r);
}
#endif

}  // namespace

int polar_lanes() {
#ifdef TESSERA_AVX_KERNELS
  if (avx_kernels_enabled()) return 4;
#endif
  return 2;
}

bool polar_lanes_3d(double* const* A, int lanes, Eigen::Index r, bool zero_tail) {
#ifdef TESSERA_AVX_KERNELS
  if (lanes == 4) return polar_avx(A, r, zero_tail);
#endif
  return polar_sse2(A, r, zero_tail);
}

}  // namespace tessera
