#include "problem/edge_lanes.hpp"

#include "util/avx_kernels.hpp"
#include "util/lanes.hpp"

namespace tessera {
namespace {

// edge_term_3x3, lane by lane: row a of the translation residual and of the rotation residual's
// columns b formed as there (element-wise), the squares added to tr and rot in its order (rows
// 0, 1, 2; in each, the translation's to tr, then columns 0, 1, 2 to rot).
template <typename V, int L>
TESSERA_LANE_INLINE void edge_terms(const double* const* xi, const double* const* xj,
                                    const double* m, double* terms) {
  constexpr Eigen::Index stride = 14;
  V rot = V{} + 0.0, tr = rot;
#pragma GCC unroll 3
  for (int a = 0; a < 3; ++a) {
    V x[3];  // row a of X_i^R
#pragma GCC unroll 3
    for (int c = 0; c < 3; ++c) gather_lanes<V, L>(x[c], xi, 3 * c + a);
    V ta, ti, t;
    gather_lanes<V, L>(ta, xj, 9 + a);
    gather_lanes<V, L>(ti, xi, 9 + a);
    ta = ta - ti;
#pragma GCC unroll 3
    for (int c = 0; c < 3; ++c) {
      gather_lanes<V, L>(t, m, stride, 9 + c);
      ta -= x[c] * t;
    }
    tr += ta * ta;
#pragma GCC unroll 3
    for (int b = 0; b < 3; ++b) {
      V v, rm;
      gather_lanes<V, L>(v, xj, 3 * b + a);
#pragma GCC unroll 3
      for (int c = 0; c < 3; ++c) {
        gather_lanes<V, L>(rm, m, stride, 3 * b + c);
        v -= x[c] * rm;
      }
      rot += v * v;
    }
  }
  V kappa, tau;
  gather_lanes<V, L>(kappa, m, stride, 12);
  gather_lanes<V, L>(tau, m, stride, 13);
  const V term = kappa * rot + tau * tr;
#pragma GCC unroll 4
  for (int l = 0; l < L; ++l) terms[l] = term[l];
}

void edge_terms_sse2(const double* const* xi, const double* const* xj, const double* m,
                     double* terms) {
  edge_terms<Lanes2, 2>(xi, xj, m, terms);
}

#ifdef TESSERA_AVX_KERNELS
__attribute__((target("avx"))) void edge_terms_avx(const double* const* xi, const double* const* xj,
                                                   const double* m, double* terms) {
  edge_terms<Lanes4, 4>(xi, xj, m, terms);
}
#endif

}  // namespace

void edge_terms_in_lanes(const double* const* xi, const double* const* xj, const double* m,
                         int lanes, double* terms) {
#ifdef TESSERA_AVX_KERNELS
  if (lanes == 4) return edge_terms_avx(xi, xj, m, terms);
#endif
  (void)lanes;
  edge_terms_sse2(xi, xj, m, terms);
}

}  // namespace tessera
