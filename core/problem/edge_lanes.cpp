#include "problem/edge_lanes.hpp"

#include "manifold/pose_lanes.hpp"
#include "util/avx_kernels.hpp"
#include "util/lanes.hpp"

namespace tessera {
namespace {

// edge_term_3x3, lane by lane: row a of the translation residual and of the rotation residual's
// columns b formed as there (element-wise), the squares added to tr and rot in its order (rows
// 0, 1, 2; in each, the translation's to tr, then columns 0, 1, 2 to rot). Then each lane's
// term to f and s in measurement order, as sum_edges adds them.
template <typename V, int L>
TESSERA_LANE_INLINE std::size_t sum_terms(const std::size_t* slots, std::size_t count,
                                          const double* X, const double* Xn, std::size_t m,
                                          const double* packed, double& f_out, double& s_out) {
  constexpr Eigen::Index stride = 14;
  double f = f_out, s = s_out;
  std::size_t k = 0;
  for (; k + L <= count; k += L) {
    const double* xi[L];
    const double* xj[L];
    bool inside[L];
#pragma GCC unroll 4
    for (int l = 0; l < L; ++l) {
      const std::size_t i = slots[2 * (k + l)], j = slots[2 * (k + l) + 1];
      xi[l] = i < m ? X + 12 * i : Xn + 12 * (i - m);
      xj[l] = j < m ? X + 12 * j : Xn + 12 * (j - m);
      inside[l] = i < m && j < m;
    }
    const double* mk = packed + stride * static_cast<Eigen::Index>(k);
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
        gather_lanes<V, L>(t, mk, stride, 9 + c);
        ta -= x[c] * t;
      }
      tr += ta * ta;
#pragma GCC unroll 3
      for (int b = 0; b < 3; ++b) {
        V v, rm;
        gather_lanes<V, L>(v, xj, 3 * b + a);
#pragma GCC unroll 3
        for (int c = 0; c < 3; ++c) {
          gather_lanes<V, L>(rm, mk, stride, 3 * b + c);
          v -= x[c] * rm;
        }
        rot += v * v;
      }
    }
    V kappa, tau;
    gather_lanes<V, L>(kappa, mk, stride, 12);
    gather_lanes<V, L>(tau, mk, stride, 13);
    const V term = kappa * rot + tau * tr;
#pragma GCC unroll 4
    for (int l = 0; l < L; ++l) {
      f += term[l];
      s += inside[l] ? term[l] : 0.5 * term[l];
    }
  }
  f_out = f;
  s_out = s;
  return k;
}

std::size_t sum_terms_sse2(const std::size_t* slots, std::size_t count, const double* X,
                           const double* Xn, std::size_t m, const double* packed, double& f,
                           double& s) {
  return sum_terms<Lanes2, 2>(slots, count, X, Xn, m, packed, f, s);
}

#ifdef TESSERA_AVX_KERNELS
__attribute__((target("avx"))) std::size_t sum_terms_avx(const std::size_t* slots,
                                                         std::size_t count, const double* X,
                                                         const double* Xn, std::size_t m,
                                                         const double* packed, double& f,
                                                         double& s) {
  return sum_terms<Lanes4, 4>(slots, count, X, Xn, m, packed, f, s);
}
#endif

}  // namespace

std::size_t sum_edge_terms_in_lanes(const std::size_t* slots, std::size_t count, const double* X,
                                    const double* Xn, std::size_t m, const double* packed,
                                    double& f, double& s) {
#ifdef TESSERA_AVX_KERNELS
  if (pose_lanes() == 4) return sum_terms_avx(slots, count, X, Xn, m, packed, f, s);
#endif
  return sum_terms_sse2(slots, count, X, Xn, m, packed, f, s);
}

}  // namespace tessera
