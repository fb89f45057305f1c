#pragma once
// Vectors of doubles for the kernels that handle several poses or measurements at once, one a
// lane: GCC's vector extension, element-wise, each lane rounded as the scalar operation (no FMA
// is ever formed: no copy is compiled with it). A kernel is a template over the vector type,
// written once and inlined (TESSERA_LANE_INLINE) into a copy per instruction set, where it is
// compiled for that set: four lanes in the AVX copy (util/avx_kernels.hpp), two in the SSE2
// one. Vectors pass by reference only: a 32-byte vector by value would change the calling
// convention of a non-AVX function.

#include <Eigen/Core>
#include <cstring>

namespace tessera {

typedef double Lanes2 __attribute__((vector_size(16)));
typedef double Lanes4 __attribute__((vector_size(32)));

#define TESSERA_LANE_INLINE inline __attribute__((always_inline))

/// v = p[0 .. lanes) (no alignment needed).
template <typename V>
TESSERA_LANE_INLINE void load_lanes(V& v, const double* p) {
  std::memcpy(&v, p, sizeof(V));
}

/// p[0 .. lanes) = v.
template <typename V>
TESSERA_LANE_INLINE void store_lanes(double* p, const V& v) {
  std::memcpy(p, &v, sizeof(V));
}

// The gathers go through a plain array: a braced vector assigned inside a loop made GCC warn
// that the target's previous value may be read uninitialised.

/// Lane l of v = p[l * stride + at].
template <typename V, int L>
TESSERA_LANE_INLINE void gather_lanes(V& v, const double* p, Eigen::Index stride, Eigen::Index at) {
  if constexpr (L == 4) {
    const double e[4] = {p[at], p[stride + at], p[2 * stride + at], p[3 * stride + at]};
    std::memcpy(&v, e, sizeof(V));
  } else {
    const double e[2] = {p[at], p[stride + at]};
    std::memcpy(&v, e, sizeof(V));
  }
}

/// Lane l of v = p[l][at].
template <typename V, int L>
TESSERA_LANE_INLINE void gather_lanes(V& v, const double* const* p, Eigen::Index at) {
  if constexpr (L == 4) {
    const double e[4] = {p[0][at], p[1][at], p[2][at], p[3][at]};
    std::memcpy(&v, e, sizeof(V));
  } else {
    const double e[2] = {p[0][at], p[1][at]};
    std::memcpy(&v, e, sizeof(V));
  }
}

/// p[l * stride + at] = lane l of v.
template <typename V, int L>
TESSERA_LANE_INLINE void scatter_lanes(const V& v, double* p, Eigen::Index stride,
                                       Eigen::Index at) {
#pragma GCC unroll 4
  for (int l = 0; l < L; ++l) p[l * stride + at] = v[l];
}

}  // namespace tessera
