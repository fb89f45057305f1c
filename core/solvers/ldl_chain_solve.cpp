#include "solvers/ldl_chain_solve.hpp"

#include <algorithm>

#include "util/avx_kernels.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace tessera {
namespace {

// The row updates of a forward chain over one run: x[k] -= a[k] y0 (+ b[k] y1 (+ c[k] y2)),
// the sum formed left to right as CHOLMOD forms it. Element-wise, so two rows to an SSE2
// register keep the bits.
void forward_run(double* x, const double* a, double y0, int length) {
  int k = 0;
#ifdef __SSE2__
  const __m128d v0 = _mm_set1_pd(y0);
#pragma GCC unroll 2
  for (; k + 2 <= length; k += 2)
    _mm_storeu_pd(x + k, _mm_sub_pd(_mm_loadu_pd(x + k), _mm_mul_pd(_mm_loadu_pd(a + k), v0)));
#endif
  for (; k < length; ++k) x[k] -= a[k] * y0;
}
void forward_run(double* x, const double* a, const double* b, double y0, double y1, int length) {
  int k = 0;
#ifdef __SSE2__
  const __m128d v0 = _mm_set1_pd(y0), v1 = _mm_set1_pd(y1);
#pragma GCC unroll 2
  for (; k + 2 <= length; k += 2) {
    const __m128d s =
        _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(a + k), v0), _mm_mul_pd(_mm_loadu_pd(b + k), v1));
    _mm_storeu_pd(x + k, _mm_sub_pd(_mm_loadu_pd(x + k), s));
  }
#endif
  for (; k < length; ++k) x[k] -= a[k] * y0 + b[k] * y1;
}
void forward_run(double* x, const double* a, const double* b, const double* c, double y0, double y1,
                 double y2, int length) {
  int k = 0;
#ifdef __SSE2__
  const __m128d v0 = _mm_set1_pd(y0), v1 = _mm_set1_pd(y1), v2 = _mm_set1_pd(y2);
#pragma GCC unroll 2
  for (; k + 2 <= length; k += 2) {
    __m128d s =
        _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(a + k), v0), _mm_mul_pd(_mm_loadu_pd(b + k), v1));
    s = _mm_add_pd(s, _mm_mul_pd(_mm_loadu_pd(c + k), v2));
    _mm_storeu_pd(x + k, _mm_sub_pd(_mm_loadu_pd(x + k), s));
  }
#endif
  for (; k < length; ++k) x[k] -= a[k] * y0 + b[k] * y1 + c[k] * y2;
}

// A backward chain's dots over its runs: y_c -= a_c[k] x[k] for k in order, each y_c its own
// sequential sum. Two rows' products are formed in one SSE2 register and subtracted low lane
// first: the same operations in the same order.
#ifdef __SSE2__
inline void subtract_pair(__m128d& y, __m128d product) {
  y = _mm_sub_sd(_mm_sub_sd(y, product), _mm_unpackhi_pd(product, product));
}
#endif

template <int W>
void backward_runs(double (&y)[3], const double* (&a)[3], const double* X,
                   const LdlChainSolve::Run* run, const LdlChainSolve::Run* end) {
  const double* a0 = a[0];
  const double* a1 = a[1];
  const double* a2 = a[2];
  double y0 = y[0], y1 = y[1], y2 = y[2];
  for (; run != end; ++run) {
    const double* x = X + run->row;
    const int length = run->length;
    int k = 0;
#ifdef __SSE2__
    __m128d s0 = _mm_set_sd(y0), s1 = _mm_set_sd(y1), s2 = _mm_set_sd(y2);
#pragma GCC unroll 2
    for (; k + 2 <= length; k += 2) {
      const __m128d xv = _mm_loadu_pd(x + k);
      subtract_pair(s0, _mm_mul_pd(_mm_loadu_pd(a0 + k), xv));
      if constexpr (W > 1) subtract_pair(s1, _mm_mul_pd(_mm_loadu_pd(a1 + k), xv));
      if constexpr (W > 2) subtract_pair(s2, _mm_mul_pd(_mm_loadu_pd(a2 + k), xv));
    }
    y0 = _mm_cvtsd_f64(s0);
    if constexpr (W > 1) y1 = _mm_cvtsd_f64(s1);
    if constexpr (W > 2) y2 = _mm_cvtsd_f64(s2);
#endif
    for (; k < length; ++k) {
      y0 -= a0[k] * x[k];
      if constexpr (W > 1) y1 -= a1[k] * x[k];
      if constexpr (W > 2) y2 -= a2[k] * x[k];
    }
    a0 += length;
    a1 += length;
    a2 += length;
  }
  y[0] = y0;
  y[1] = y1;
  y[2] = y2;
}

// backward_runs<W> with split dots (LdlChainSolve::set_split_dots): four partial sums per
// column, lane l taking each run's rows k = l mod 4, lane 0 starting from y_c, the others from
// 0; at the end y_c = (l0 + l2) + (l1 + l3). Lanes 0-1 and 2-3 are two SSE2 registers here and
// one AVX register below: the same operations on every lane, so the same bits.
template <int W>
void backward_runs_split(double (&y)[3], const double* (&a)[3], const double* X,
                         const LdlChainSolve::Run* run, const LdlChainSolve::Run* end) {
  const double* a0 = a[0];
  const double* a1 = a[1];
  const double* a2 = a[2];
#ifdef __SSE2__
  __m128d lo0 = _mm_set_sd(y[0]), lo1 = _mm_set_sd(y[1]), lo2 = _mm_set_sd(y[2]);
  __m128d hi0 = _mm_setzero_pd(), hi1 = hi0, hi2 = hi0;
  for (; run != end; ++run) {
    const double* x = X + run->row;
    const int length = run->length;
    int k = 0;
    for (; k + 4 <= length; k += 4) {
      const __m128d xl = _mm_loadu_pd(x + k), xh = _mm_loadu_pd(x + k + 2);
      lo0 = _mm_sub_pd(lo0, _mm_mul_pd(_mm_loadu_pd(a0 + k), xl));
      hi0 = _mm_sub_pd(hi0, _mm_mul_pd(_mm_loadu_pd(a0 + k + 2), xh));
      if constexpr (W > 1) {
        lo1 = _mm_sub_pd(lo1, _mm_mul_pd(_mm_loadu_pd(a1 + k), xl));
        hi1 = _mm_sub_pd(hi1, _mm_mul_pd(_mm_loadu_pd(a1 + k + 2), xh));
      }
      if constexpr (W > 2) {
        lo2 = _mm_sub_pd(lo2, _mm_mul_pd(_mm_loadu_pd(a2 + k), xl));
        hi2 = _mm_sub_pd(hi2, _mm_mul_pd(_mm_loadu_pd(a2 + k + 2), xh));
      }
    }
    if (k + 2 <= length) {  // lanes 0-1, then lane 2
      const __m128d xl = _mm_loadu_pd(x + k);
      lo0 = _mm_sub_pd(lo0, _mm_mul_pd(_mm_loadu_pd(a0 + k), xl));
      if constexpr (W > 1) lo1 = _mm_sub_pd(lo1, _mm_mul_pd(_mm_loadu_pd(a1 + k), xl));
      if constexpr (W > 2) lo2 = _mm_sub_pd(lo2, _mm_mul_pd(_mm_loadu_pd(a2 + k), xl));
      k += 2;
      if (k < length) {
        const __m128d xs = _mm_load_sd(x + k);
        hi0 = _mm_sub_sd(hi0, _mm_mul_sd(_mm_load_sd(a0 + k), xs));
        if constexpr (W > 1) hi1 = _mm_sub_sd(hi1, _mm_mul_sd(_mm_load_sd(a1 + k), xs));
        if constexpr (W > 2) hi2 = _mm_sub_sd(hi2, _mm_mul_sd(_mm_load_sd(a2 + k), xs));
      }
    } else if (k < length) {  // lane 0
      const __m128d xs = _mm_load_sd(x + k);
      lo0 = _mm_sub_sd(lo0, _mm_mul_sd(_mm_load_sd(a0 + k), xs));
      if constexpr (W > 1) lo1 = _mm_sub_sd(lo1, _mm_mul_sd(_mm_load_sd(a1 + k), xs));
      if constexpr (W > 2) lo2 = _mm_sub_sd(lo2, _mm_mul_sd(_mm_load_sd(a2 + k), xs));
    }
    a0 += length;
    a1 += length;
    a2 += length;
  }
  auto reduce = [](__m128d lo, __m128d hi) {
    const __m128d t = _mm_add_pd(lo, hi);
    return _mm_cvtsd_f64(_mm_add_sd(t, _mm_unpackhi_pd(t, t)));
  };
  y[0] = reduce(lo0, hi0);
  if constexpr (W > 1) y[1] = reduce(lo1, hi1);
  if constexpr (W > 2) y[2] = reduce(lo2, hi2);
#else
  double s[3][4] = {{y[0], 0, 0, 0}, {y[1], 0, 0, 0}, {y[2], 0, 0, 0}};
  for (; run != end; ++run) {
    const double* x = X + run->row;
    for (int k = 0; k < run->length; ++k) {
      s[0][k % 4] -= a0[k] * x[k];
      if constexpr (W > 1) s[1][k % 4] -= a1[k] * x[k];
      if constexpr (W > 2) s[2][k % 4] -= a2[k] * x[k];
    }
    a0 += run->length;
    a1 += run->length;
    a2 += run->length;
  }
  for (int c = 0; c < W; ++c) y[c] = (s[c][0] + s[c][2]) + (s[c][1] + s[c][3]);
#endif
}

// The baseline kernels, as the solve's chain loop calls them.
struct Sse2Kernels {
  template <class... Args>
  static void forward_run(Args... args) {
    ::tessera::forward_run(args...);
  }
  template <int W, bool Split>
  static void backward_runs(double (&y)[3], const double* (&a)[3], const double* X,
                            const LdlChainSolve::Run* run, const LdlChainSolve::Run* end) {
    if constexpr (Split)
      ::tessera::backward_runs_split<W>(y, a, X, run, end);
    else
      ::tessera::backward_runs<W>(y, a, X, run, end);
  }
};

#ifdef TESSERA_AVX_KERNELS
// The same row updates and dots with four rows to an AVX register (no FMA: each product is
// rounded before it is added, as above), so the same values.
struct AvxKernels {
  __attribute__((target("avx"))) static void forward_run(double* x, const double* a, double y0,
                                                         int length) {
    int k = 0;
    const __m256d v0 = _mm256_set1_pd(y0);
    for (; k + 4 <= length; k += 4)
      _mm256_storeu_pd(
          x + k, _mm256_sub_pd(_mm256_loadu_pd(x + k), _mm256_mul_pd(_mm256_loadu_pd(a + k), v0)));
    if (k + 2 <= length) {
      const __m128d w0 = _mm256_castpd256_pd128(v0);
      _mm_storeu_pd(x + k, _mm_sub_pd(_mm_loadu_pd(x + k), _mm_mul_pd(_mm_loadu_pd(a + k), w0)));
      k += 2;
    }
    for (; k < length; ++k) x[k] -= a[k] * y0;
  }
  __attribute__((target("avx"))) static void forward_run(double* x, const double* a,
                                                         const double* b, double y0, double y1,
                                                         int length) {
    int k = 0;
    const __m256d v0 = _mm256_set1_pd(y0), v1 = _mm256_set1_pd(y1);
    for (; k + 4 <= length; k += 4) {
      const __m256d s = _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(a + k), v0),
                                      _mm256_mul_pd(_mm256_loadu_pd(b + k), v1));
      _mm256_storeu_pd(x + k, _mm256_sub_pd(_mm256_loadu_pd(x + k), s));
    }
    if (k + 2 <= length) {
      const __m128d s = _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(a + k), _mm256_castpd256_pd128(v0)),
                                   _mm_mul_pd(_mm_loadu_pd(b + k), _mm256_castpd256_pd128(v1)));
      _mm_storeu_pd(x + k, _mm_sub_pd(_mm_loadu_pd(x + k), s));
      k += 2;
    }
    for (; k < length; ++k) x[k] -= a[k] * y0 + b[k] * y1;
  }
  __attribute__((target("avx"))) static void forward_run(double* x, const double* a,
                                                         const double* b, const double* c,
                                                         double y0, double y1, double y2,
                                                         int length) {
    int k = 0;
    const __m256d v0 = _mm256_set1_pd(y0), v1 = _mm256_set1_pd(y1), v2 = _mm256_set1_pd(y2);
    for (; k + 4 <= length; k += 4) {
      __m256d s = _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(a + k), v0),
                                _mm256_mul_pd(_mm256_loadu_pd(b + k), v1));
      s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(c + k), v2));
      _mm256_storeu_pd(x + k, _mm256_sub_pd(_mm256_loadu_pd(x + k), s));
    }
    if (k + 2 <= length) {
      __m128d s = _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(a + k), _mm256_castpd256_pd128(v0)),
                             _mm_mul_pd(_mm_loadu_pd(b + k), _mm256_castpd256_pd128(v1)));
      s = _mm_add_pd(s, _mm_mul_pd(_mm_loadu_pd(c + k), _mm256_castpd256_pd128(v2)));
      _mm_storeu_pd(x + k, _mm_sub_pd(_mm_loadu_pd(x + k), s));
      k += 2;
    }
    for (; k < length; ++k) x[k] -= a[k] * y0 + b[k] * y1 + c[k] * y2;
  }

  template <int W, bool Split>
  __attribute__((target("avx"))) static void backward_runs(double (&y)[3], const double* (&a)[3],
                                                           const double* X,
                                                           const LdlChainSolve::Run* run,
                                                           const LdlChainSolve::Run* end) {
    if constexpr (Split)
      backward_runs_split<W>(y, a, X, run, end);
    else
      backward_runs_sequential<W>(y, a, X, run, end);
  }

  // backward_runs_split<W> (above) with the four lanes in one register. A run's last 1-3 rows
  // are loaded masked: the other lanes subtract 0 * 0 = +0, which leaves any value as it is.
  template <int W>
  __attribute__((target("avx"))) static void backward_runs_split(double (&y)[3],
                                                                 const double* (&a)[3],
                                                                 const double* X,
                                                                 const LdlChainSolve::Run* run,
                                                                 const LdlChainSolve::Run* end) {
    alignas(32) static const long long kMasks[4][4] = {
        {0, 0, 0, 0}, {-1, 0, 0, 0}, {-1, -1, 0, 0}, {-1, -1, -1, 0}};
    const double* a0 = a[0];
    const double* a1 = a[1];
    const double* a2 = a[2];
    __m256d s0 = _mm256_set_pd(0.0, 0.0, 0.0, y[0]);
    __m256d s1 = _mm256_set_pd(0.0, 0.0, 0.0, y[1]);
    __m256d s2 = _mm256_set_pd(0.0, 0.0, 0.0, y[2]);
    for (; run != end; ++run) {
      const double* x = X + run->row;
      const int length = run->length;
      int k = 0;
      for (; k + 4 <= length; k += 4) {
        const __m256d xv = _mm256_loadu_pd(x + k);
        s0 = _mm256_sub_pd(s0, _mm256_mul_pd(_mm256_loadu_pd(a0 + k), xv));
        if constexpr (W > 1) s1 = _mm256_sub_pd(s1, _mm256_mul_pd(_mm256_loadu_pd(a1 + k), xv));
        if constexpr (W > 2) s2 = _mm256_sub_pd(s2, _mm256_mul_pd(_mm256_loadu_pd(a2 + k), xv));
      }
      if (k < length) {
        const __m256i mask =
            _mm256_load_si256(reinterpret_cast<const __m256i*>(kMasks[length - k]));
        const __m256d xv = _mm256_maskload_pd(x + k, mask);
        s0 = _mm256_sub_pd(s0, _mm256_mul_pd(_mm256_maskload_pd(a0 + k, mask), xv));
        if constexpr (W > 1)
          s1 = _mm256_sub_pd(s1, _mm256_mul_pd(_mm256_maskload_pd(a1 + k, mask), xv));
        if constexpr (W > 2)
          s2 = _mm256_sub_pd(s2, _mm256_mul_pd(_mm256_maskload_pd(a2 + k, mask), xv));
      }
      a0 += length;
      a1 += length;
      a2 += length;
    }
    y[0] = reduce(s0);
    if constexpr (W > 1) y[1] = reduce(s1);
    if constexpr (W > 2) y[2] = reduce(s2);
  }

 private:
  // backward_runs<W> with four rows' products in one register, subtracted lane by lane in row
  // order (two SSE2 pairs, low lane first).
  template <int W>
  __attribute__((target("avx"))) static void backward_runs_sequential(
      double (&y)[3], const double* (&a)[3], const double* X, const LdlChainSolve::Run* run,
      const LdlChainSolve::Run* end) {
    const double* a0 = a[0];
    const double* a1 = a[1];
    const double* a2 = a[2];
    __m128d s0 = _mm_set_sd(y[0]), s1 = _mm_set_sd(y[1]), s2 = _mm_set_sd(y[2]);
    for (; run != end; ++run) {
      const double* x = X + run->row;
      const int length = run->length;
      int k = 0;
      for (; k + 4 <= length; k += 4) {
        const __m256d xv = _mm256_loadu_pd(x + k);
        subtract_quad(s0, _mm256_mul_pd(_mm256_loadu_pd(a0 + k), xv));
        if constexpr (W > 1) subtract_quad(s1, _mm256_mul_pd(_mm256_loadu_pd(a1 + k), xv));
        if constexpr (W > 2) subtract_quad(s2, _mm256_mul_pd(_mm256_loadu_pd(a2 + k), xv));
      }
      if (k + 2 <= length) {
        const __m128d xv = _mm_loadu_pd(x + k);
        subtract_pair(s0, _mm_mul_pd(_mm_loadu_pd(a0 + k), xv));
        if constexpr (W > 1) subtract_pair(s1, _mm_mul_pd(_mm_loadu_pd(a1 + k), xv));
        if constexpr (W > 2) subtract_pair(s2, _mm_mul_pd(_mm_loadu_pd(a2 + k), xv));
        k += 2;
      }
      if (k < length) {
        const __m128d xv = _mm_load_sd(x + k);
        s0 = _mm_sub_sd(s0, _mm_mul_sd(_mm_load_sd(a0 + k), xv));
        if constexpr (W > 1) s1 = _mm_sub_sd(s1, _mm_mul_sd(_mm_load_sd(a1 + k), xv));
        if constexpr (W > 2) s2 = _mm_sub_sd(s2, _mm_mul_sd(_mm_load_sd(a2 + k), xv));
      }
      a0 += length;
      a1 += length;
      a2 += length;
    }
    y[0] = _mm_cvtsd_f64(s0);
    y[1] = _mm_cvtsd_f64(s1);
    y[2] = _mm_cvtsd_f64(s2);
  }

  // (l0 + l2) + (l1 + l3), as the SSE2 copy sums its two registers.
  __attribute__((target("avx"))) static double reduce(__m256d s) {
    const __m128d t = _mm_add_pd(_mm256_castpd256_pd128(s), _mm256_extractf128_pd(s, 1));
    return _mm_cvtsd_f64(_mm_add_sd(t, _mm_unpackhi_pd(t, t)));
  }
  __attribute__((target("avx"))) static void subtract_pair(__m128d& y, __m128d product) {
    y = _mm_sub_sd(_mm_sub_sd(y, product), _mm_unpackhi_pd(product, product));
  }
  __attribute__((target("avx"))) static void subtract_quad(__m128d& y, __m256d product) {
    subtract_pair(y, _mm256_castpd256_pd128(product));
    subtract_pair(y, _mm256_extractf128_pd(product, 1));
  }
};
#endif

}  // namespace

void LdlChainSolve::clear() {
  forward_.clear();
  backward_.clear();
  forward_runs_.clear();
  backward_runs_.clear();
  ready_ = false;
}

void LdlChainSolve::add_runs(const int* rows, int count, std::vector<Run>& runs) {
  for (int t = 0; t < count;) {
    int length = 1;
    while (t + length < count && rows[t + length] == rows[t] + length) ++length;
    runs.push_back({rows[t], length});
    t += length;
  }
}

bool LdlChainSolve::build(const cholmod_factor* L) {
  clear();
  if (L == nullptr || L->is_super || L->is_ll || L->xtype != CHOLMOD_REAL ||
      L->itype != CHOLMOD_INT || L->dtype != CHOLMOD_DOUBLE || L->x == nullptr)
    return false;
  const int n = static_cast<int>(L->n);
  const auto* Lp = static_cast<const int*>(L->p);
  const auto* Li = static_cast<const int*>(L->i);
  const auto* Lnz = static_cast<const int*>(L->nz);
  // CHOLMOD's forward chain test (j, j+1, j+2 share their rows below the chain).
  for (int j = 0; j < n;) {
    const int p = Lp[j], lnz = Lnz[j];
    int width = 3;
    if (lnz < 4 || lnz != Lnz[j + 1] + 1 || Li[p + 1] != j + 1)
      width = 1;
    else if (lnz != Lnz[j + 2] + 2 || Li[p + 2] != j + 2)
      width = 2;
    const int begin = static_cast<int>(forward_runs_.size());
    add_runs(Li + p + width, lnz - width, forward_runs_);
    forward_.push_back({j, width, begin, static_cast<int>(forward_runs_.size())});
    j += width;
  }
  // Its backward chain test (j, j-1, j-2), from the last column.
  for (int j = n - 1; j >= 0;) {
    const int p = Lp[j], lnz = Lnz[j];
    int width = 3;
    if (j < 4 || lnz != Lnz[j - 1] - 1 || Li[Lp[j - 1] + 1] != j)
      width = 1;
    else if (lnz != Lnz[j - 2] - 2 || Li[Lp[j - 2] + 2] != j)
      width = 2;
    const int begin = static_cast<int>(backward_runs_.size());
    add_runs(Li + p + 1, lnz - 1, backward_runs_);
    backward_.push_back({j, width, begin, static_cast<int>(backward_runs_.size())});
    j -= width;
  }
  y_.assign(static_cast<std::size_t>(n), 0.0);
  ready_ = true;
  return true;
}

void LdlChainSolve::solve(const cholmod_factor* L, const double* rhs, double* out) const {
  const int n = static_cast<int>(L->n);
  const auto* perm = static_cast<const int*>(L->Perm);
  double* X = y_.data();
  // The permutation test outside the loops (-O2 does not unswitch them).
  if (perm)
    for (int k = 0; k < n; ++k) X[k] = rhs[perm[k]];
  else
    std::copy(rhs, rhs + n, X);
#ifdef TESSERA_AVX_KERNELS
  if (avx_kernels_enabled()) {
    if (split_dots_)
      solve_chains_avx_split(L, X);
    else
      solve_chains_avx(L, X);
  } else
#endif
      if (split_dots_)
    solve_chains_sse2_split(L, X);
  else
    solve_chains_sse2(L, X);
  if (perm)
    for (int k = 0; k < n; ++k) out[perm[k]] = X[k];
  else
    std::copy(X, X + n, out);
}

// Each kernel set's chain loop as its own function with its kernels inlined (both inlined
// into solve(), GCC called the kernels instead).
__attribute__((flatten)) void LdlChainSolve::solve_chains_sse2(const cholmod_factor* L,
                                                               double* X) const {
  solve_chains<Sse2Kernels, false>(L, X);
}
__attribute__((flatten)) void LdlChainSolve::solve_chains_sse2_split(const cholmod_factor* L,
                                                                     double* X) const {
  solve_chains<Sse2Kernels, true>(L, X);
}

#ifdef TESSERA_AVX_KERNELS
// The chain loops compiled for AVX, so that the AVX kernels inline into them.
__attribute__((target("avx"), flatten)) void LdlChainSolve::solve_chains_avx(
    const cholmod_factor* L, double* X) const {
  solve_chains<AvxKernels, false>(L, X);
}
__attribute__((target("avx"), flatten)) void LdlChainSolve::solve_chains_avx_split(
    const cholmod_factor* L, double* X) const {
  solve_chains<AvxKernels, true>(L, X);
}
#endif

template <class Kernels, bool Split>
inline __attribute__((always_inline)) void LdlChainSolve::solve_chains(const cholmod_factor* L,
                                                                       double* X) const {
  const auto* Lp = static_cast<const int*>(L->p);
  const auto* Lx = static_cast<const double*>(L->x);
  // L y = P b (unit diagonal).
  for (const Chain& ch : forward_) {
    const int j = ch.column, p = Lp[j];
    const Run* run = forward_runs_.data() + ch.run_begin;
    const Run* end = forward_runs_.data() + ch.run_end;
    if (ch.width == 1) {
      const double y0 = X[j];
      const double* a = Lx + p + 1;
      for (; run != end; a += run->length, ++run)
        Kernels::forward_run(X + run->row, a, y0, run->length);
    } else if (ch.width == 2) {
      const int q = Lp[j + 1];
      const double y0 = X[j];
      const double y1 = X[j + 1] - Lx[p + 1] * y0;
      X[j + 1] = y1;
      const double* a = Lx + p + 2;
      const double* b = Lx + q + 1;
      for (; run != end; a += run->length, b += run->length, ++run)
        Kernels::forward_run(X + run->row, a, b, y0, y1, run->length);
    } else {
      const int q = Lp[j + 1], r = Lp[j + 2];
      const double y0 = X[j];
      const double y1 = X[j + 1] - Lx[p + 1] * y0;
      const double y2 = X[j + 2] - Lx[p + 2] * y0 - Lx[q + 1] * y1;
      X[j + 1] = y1;
      X[j + 2] = y2;
      const double* a = Lx + p + 3;
      const double* b = Lx + q + 2;
      const double* c = Lx + r + 1;
      for (; run != end; a += run->length, b += run->length, c += run->length, ++run)
        Kernels::forward_run(X + run->row, a, b, c, y0, y1, y2, run->length);
    }
  }

  // D L^T x = y: each column divided by its D entry first, then its dot with the rows below
  // subtracted in the factor's row order (or, with Split, as four partial sums).
  for (const Chain& ch : backward_) {
    const int j = ch.column, w = ch.width;
    const Run* run = backward_runs_.data() + ch.run_begin;
    const Run* end = backward_runs_.data() + ch.run_end;
    // Column j - c: its diagonal at Lp[j - c], then c entries inside the chain, then the rows.
    int col[3] = {Lp[j], 0, 0};
    double y[3] = {X[j] / Lx[col[0]], 0.0, 0.0};
    for (int c = 1; c < w; ++c) {
      col[c] = Lp[j - c];
      y[c] = X[j - c] / Lx[col[c]];
    }
    const double* a[3] = {Lx + col[0] + 1, Lx + col[1] + 2, Lx + col[2] + 3};
    if (w == 3)
      Kernels::template backward_runs<3, Split>(y, a, X, run, end);
    else if (w == 2)
      Kernels::template backward_runs<2, Split>(y, a, X, run, end);
    else
      Kernels::template backward_runs<1, Split>(y, a, X, run, end);
    if (w == 2) {
      y[1] -= Lx[col[1] + 1] * y[0];
    } else if (w == 3) {
      y[1] -= Lx[col[1] + 1] * y[0];
      y[2] -= Lx[col[2] + 2] * y[0] + Lx[col[2] + 1] * y[1];
    }
    for (int c = w - 1; c >= 0; --c) X[j - c] = y[c];
  }
}

}  // namespace tessera
