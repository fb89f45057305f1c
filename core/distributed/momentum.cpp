#include <Eigen/Eigenvalues>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#include <cmath>
#include <stdexcept>
#include <string>
#include <tessera/distributed/momentum.hpp>
#include <utility>

#include "manifold/pose_lanes.hpp"
#include "util/avx_kernels.hpp"
#include "util/lanes.hpp"

namespace tessera {
namespace {

// ||E||_F of a 3 x 3 E in the order of Eigen 3.4's vectorised E.norm() (two-lane packets of the
// column-major entries 0-7 summed pairwise, the lanes added, then entry 8): the same value, so
// the same branches below as with E.norm().
inline double frobenius_norm_3(const double (&E)[3][3]) {
  auto sq = [](double x) { return x * x; };
  const double lane0 = (sq(E[0][0]) + sq(E[2][0])) + (sq(E[1][1]) + sq(E[0][2]));
  const double lane1 = (sq(E[1][0]) + sq(E[0][1])) + (sq(E[2][1]) + sq(E[1][2]));
  return std::sqrt((lane0 + lane1) + sq(E[2][2]));
}

// Proj_M pose by pose. The polar factor of an r x d block A is A (A^T A)^{-1/2}. The points
// projected here (convex combinations of nearby manifold points) are close to the manifold:
// with B = A^T A = I - E, ||E|| is below 1e-4 for all but ~0.3 % of the poses of a round
// (sphere2500: ~1e-10 to 1e-6 mostly), where the binomial series
// B^{-1/2} = I + E/2 + 3E^2/8 + 5E^3/16 + 35E^4/128 + ... cut after E^3 is exact to
// 35/128 ||E||^4 < 3e-17, below the rounding of the sum (and after E, below 1e-9, to
// 3/8 ||E||^2 < 4e-19). Farther points take the coupled Newton-Schulz iteration for B^{-1/2}
// (Y <- Y T, Z <- T Z, T = (3I - Z Y)/2; Y -> I, Z -> B^{-1/2}), quadratic in a few d x d
// products; points far from the manifold the d x d eigen-decomposition, (nearly) rank-deficient
// ones the SVD. Everything lives on the stack: these projections run on every pose of every
// agent each round.
template <int D>
bool inv_sqrt_near_identity(const Eigen::Matrix<double, D, D>& B, Eigen::Matrix<double, D, D>& Z) {
  using Small = Eigen::Matrix<double, D, D>;
  // E = I - B and T = I + E/2 entry by entry, as the Eigen expressions of the Newton-Schulz
  // start computed them (no temporaries: this runs twice per pose and round).
  double e1[D][D];
#pragma GCC unroll 3
  for (int j = 0; j < D; ++j)
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i) e1[i][j] = (i == j ? 1.0 : 0.0) - B(i, j);
  double e = 0.0;
  if constexpr (D == 3) {
    e = frobenius_norm_3(e1);
  } else {
    Small E;
    for (int j = 0; j < D; ++j)
      for (int i = 0; i < D; ++i) E(i, j) = e1[i][j];
    e = E.norm();
  }
  if (!(e < 0.5)) return false;
#pragma GCC unroll 3
  for (int j = 0; j < D; ++j)
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i) Z(i, j) = (i == j ? 1.0 : 0.0) + 0.5 * e1[i][j];
  if (e < 1e-9) return true;
  if (e < 1e-4) {
    // E is symmetric (B is), so are its powers: their upper triangles, mirrored. Entries (i, j)
    // and (j, i) of E^2 are the same products in the same order: E^2 is symmetric to the bit.
    double e2[D][D], e3[D][D];
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
      for (int j = i; j < D; ++j) {
        double s = e1[i][0] * e1[0][j];
#pragma GCC unroll 3
        for (int k = 1; k < D; ++k) s += e1[i][k] * e1[k][j];
        e2[i][j] = e2[j][i] = s;
      }
#pragma GCC unroll 3
    for (int i = 0; i < D; ++i)
#pragma GCC unroll 3
      for (int j = i; j < D; ++j) {
        double s = e2[i][0] * e1[0][j];
#pragma GCC unroll 3
        for (int k = 1; k < D; ++k) s += e2[i][k] * e1[k][j];
        e3[i][j] = e3[j][i] = s;
      }
      // The small terms first, then the identity.
#pragma GCC unroll 3
    for (int j = 0; j < D; ++j)
#pragma GCC unroll 3
      for (int i = 0; i < D; ++i)
        Z(i, j) = (i == j ? 1.0 : 0.0) + (0.5 * e1[i][j] + (0.375 * e2[i][j] + 0.3125 * e3[i][j]));
    return true;
  }
  // Newton-Schulz from Z = T. The first step has Z = I: E = I - B and Z = T without the two
  // products by I (equal to them up to the sign of exact zeros). The last step's Y update is not
  // used: skipped.
  const Small I = Small::Identity();
  Small T = Z, E;
  Small Y = B * T;
  for (int it = 1; it < 12; ++it) {
    E = I - Z * Y;
    e = E.norm();
    T = I + 0.5 * E;
    Z = (T * Z).eval();
    if (e < 1e-9) return true;  // quadratic convergence: this last step took it to ~1e-17
    Y = (Y * T).eval();
  }
  return false;
}

// sum_k x[k] y[k] for k < n, added in the order of Eigen 3.4's vectorised reduction of a
// dynamic-length product with two-double packets (lanes of even and odd k, two packets per step,
// then the lanes, then the odd tail), which is how `A.transpose() * A` formed each entry of
// A^T A in the previous version. Keeping that order keeps Proj_M bit-identical to it (and so
// every iterate of a run) while the hand-written loop skips Eigen's per-coefficient dispatch.
// N > 0: n is N (the loop then unrolls for the common ranks).
template <int N>
inline double gram_entry(const double* x, const double* y, Eigen::Index n_runtime) {
  const Eigen::Index n = N > 0 ? N : n_runtime;
  if (n < 2) return n == 1 ? x[0] * y[0] : 0.0;
  const Eigen::Index n2 = n / 2 * 2, n4 = n / 4 * 4;
  double l0 = x[0] * y[0], l1 = x[1] * y[1];
  if (n2 > 2) {
    double h0 = x[2] * y[2], h1 = x[3] * y[3];
    for (Eigen::Index k = 4; k < n4; k += 4) {
      l0 += x[k] * y[k];
      l1 += x[k + 1] * y[k + 1];
      h0 += x[k + 2] * y[k + 2];
      h1 += x[k + 3] * y[k + 3];
    }
    l0 += h0;
    l1 += h1;
    if (n2 > n4) {
      l0 += x[n4] * y[n4];
      l1 += x[n4 + 1] * y[n4 + 1];
    }
  }
  double s = l0 + l1;
  for (Eigen::Index k = n2; k < n; ++k) s += x[k] * y[k];
  return s;
}

// gram_entry<5> of two columns whose rows D..4 are zero, without those rows: the terms it
// drops are exact zeros, and the ones it keeps are added in gram_entry<5>'s order (lanes of even
// and odd k), so the sum has the same value.
template <int D>
inline double gram_entry_zero_tail(const double* x, const double* y) {
  if constexpr (D == 3) return (x[0] * y[0] + x[2] * y[2]) + x[1] * y[1];
  return x[0] * y[0] + x[1] * y[1];
}

// True when rows D..R-1 of the r x D Stiefel block at A are zero: a pose of the lifted start
// ([I_d; 0] R, chordal or distributed) keeps r - d zero rows through every blend and projection
// until a saddle escape fills them.
template <int D, int R>
inline bool zero_tail(const double* A) {
  bool zero = true;
  for (int a = 0; a < D; ++a)
    for (int k = D; k < R; ++k) zero = zero && A[a * R + k] == 0.0;
  return zero;
}

// Replaces the r x D column-major Stiefel block at A by its polar factor (R > 0: r is R).
template <int D, int R>
void project_pose(double* A, Eigen::Index r_runtime) {
  const Eigen::Index r = R > 0 ? R : r_runtime;
  using Small = Eigen::Matrix<double, D, D>;
  // P and V are kept at the relaxation rank (5) but only their first d rows are non-zero while
  // the run stays at its lifted start's rows: the Gram matrix and the product then skip the zero
  // rows (a third to a half of a projection's arithmetic), with the same values.
  constexpr bool kCanSkip = R == 5 && D < R;
  const bool skip = kCanSkip && zero_tail<D, (R > 0 ? R : 1)>(A);
  Small B;
  // Two loops rather than one with the choice inside, so that each unrolls.
  if (skip) {
#pragma GCC unroll 3
    for (int a = 0; a < D; ++a)
#pragma GCC unroll 3
      for (int b = a; b < D; ++b) B(a, b) = B(b, a) = gram_entry_zero_tail<D>(A + a * r, A + b * r);
  } else {
    for (int a = 0; a < D; ++a)
      for (int b = a; b < D; ++b) B(a, b) = B(b, a) = gram_entry<R>(A + a * r, A + b * r, r);
  }
  Small inv_sqrt;
  if (!inv_sqrt_near_identity<D>(B, inv_sqrt)) {
    Eigen::SelfAdjointEigenSolver<Small> es(B);
    const auto& l = es.eigenvalues();
    Eigen::Map<Eigen::MatrixXd> block(A, r, D);
    if (!(l(0) > 1e-12 * l(D - 1))) {  // (nearly) rank deficient: take the SVD's choice
      block = polar_factor(Eigen::MatrixXd(block));
      return;
    }
    inv_sqrt = es.eigenvectors() * l.cwiseSqrt().cwiseInverse().asDiagonal() *
               es.eigenvectors().transpose();
  }
  // Row by row, each entry summed over k in order (as the lazy product A * inv_sqrt did). Zero
  // rows stay zero.
  const Eigen::Index rows = skip ? D : r;
  Eigen::Index i = 0;
#ifdef __SSE2__
  // Two rows to a register: the rows of a column are adjacent in A, and each entry's sum is
  // formed as below (element-wise, so the same values).
  if (rows >= 2) {
    __m128d m[D][D];
#pragma GCC unroll 4
    for (int k = 0; k < D; ++k)
#pragma GCC unroll 4
      for (int j = 0; j < D; ++j) m[k][j] = _mm_set1_pd(inv_sqrt(k, j));
    for (; i + 2 <= rows; i += 2) {
      __m128d column[D], out[D];
#pragma GCC unroll 4
      for (int k = 0; k < D; ++k) column[k] = _mm_loadu_pd(A + k * r + i);
#pragma GCC unroll 4
      for (int j = 0; j < D; ++j) {
        __m128d s = _mm_mul_pd(column[0], m[0][j]);
#pragma GCC unroll 4
        for (int k = 1; k < D; ++k) s = _mm_add_pd(s, _mm_mul_pd(column[k], m[k][j]));
        out[j] = s;
      }
#pragma GCC unroll 4
      for (int j = 0; j < D; ++j) _mm_storeu_pd(A + j * r + i, out[j]);
    }
  }
#endif
  for (; i < rows; ++i) {
    double row[D];
#pragma GCC unroll 4
    for (int j = 0; j < D; ++j) {
      double s = A[i] * inv_sqrt(0, j);
#pragma GCC unroll 4
      for (int k = 1; k < D; ++k) s += A[k * r + i] * inv_sqrt(k, j);
      row[j] = s;
    }
#pragma GCC unroll 4
    for (int j = 0; j < D; ++j) A[j * r + i] = row[j];
  }
}

// Proj_M applied pose by pose to out, after `blend` has written each pose's unprojected value
// (r x (D+1), column-major) into out's storage for that pose. Pose i's output depends on pose
// i's inputs only, so `out` may be one of the inputs.
template <int D, int R, typename Blend>
void blend_and_project(Eigen::MatrixXd& out, Eigen::Index poses, const Blend& blend) {
  const Eigen::Index r = out.rows(), w = (D + 1) * r;
  double* base = out.data();
  Eigen::Index i = 0;
  if constexpr (D == 3 && (R == 3 || R == 5)) {
    // pose_lanes() poses at a time, one a vector lane (the same bits as pose by pose); a group
    // with a pose outside the series' reach, or (R = 5) with non-zero rows 3-4, goes pose by pose.
    const int lanes = pose_lanes();
    for (; i + lanes <= poses; i += lanes) {
      double* group = base + i * w;
      bool zero_tails = true;
      blend(i * w, lanes * w, group);  // the group's poses are consecutive
      if constexpr (R == 5)
        for (int l = 0; l < lanes; ++l) zero_tails = zero_tails && zero_tail<3, 5>(group + l * w);
      if (!zero_tails || !polar_in_lanes(group, lanes, r))
        for (int l = 0; l < lanes; ++l) project_pose<D, R>(group + l * w, r);
    }
  }
  for (; i < poses; ++i) {
    blend(i * w, w, base + i * w);
    project_pose<D, R>(base + i * w, r);
  }
}

// The ranks that occur every round: r = d (the block update's retraction on the active rows)
// and the default relaxation rank 5 (P and V keep all rows).
template <int D, typename Blend>
void blend_and_project(Eigen::MatrixXd& out, Eigen::Index poses, const Blend& blend) {
  if (out.rows() == D)
    blend_and_project<D, D>(out, poses, blend);
  else if (out.rows() == 5)
    blend_and_project<D, 5>(out, poses, blend);
  else
    blend_and_project<D, 0>(out, poses, blend);
}

template <typename Blend>
void blend_and_project(const LiftedManifold& M, Eigen::MatrixXd& out, const Blend& blend) {
  const Eigen::Index poses = out.cols() / (M.dim() + 1);
  if (M.dim() == 2)
    blend_and_project<2>(out, poses, blend);
  else
    blend_and_project<3>(out, poses, blend);
}

// The momentum blends, element by element over n doubles (dst may be v's): four at a time in
// the AVX copy, two in the SSE2 one, the rest one by one; element-wise, so the same values.
template <typename V, int L>
TESSERA_LANE_INLINE void extrapolate_blend(double a, double one_minus_a, const double* v,
                                           const double* y, double* dst, Eigen::Index n) {
  Eigen::Index k = 0;
  for (; k + L <= n; k += L) {
    V vk, yk;
    load_lanes(vk, v + k);
    load_lanes(yk, y + k);
    const V out = a * vk + one_minus_a * yk;
    store_lanes(dst + k, out);
  }
  if constexpr (L == 4)
    if (k + 2 <= n)
      return extrapolate_blend<Lanes2, 2>(a, one_minus_a, v + k, y + k, dst + k, n - k);
  for (; k < n; ++k) dst[k] = a * v[k] + one_minus_a * y[k];
}

template <typename V, int L>
TESSERA_LANE_INLINE void momentum_blend(double b, double one_minus_b, double g, const double* v,
                                        const double* p, const double* y, double* dst,
                                        Eigen::Index n) {
  Eigen::Index k = 0;
  for (; k + L <= n; k += L) {
    V vk, pk, yk;
    load_lanes(vk, v + k);
    load_lanes(pk, p + k);
    load_lanes(yk, y + k);
    const V out = (b * vk + one_minus_b * pk) + g * (yk - pk);
    store_lanes(dst + k, out);
  }
  if constexpr (L == 4)
    if (k + 2 <= n)
      return momentum_blend<Lanes2, 2>(b, one_minus_b, g, v + k, p + k, y + k, dst + k, n - k);
  for (; k < n; ++k) dst[k] = (b * v[k] + one_minus_b * p[k]) + g * (y[k] - p[k]);
}

#ifdef TESSERA_AVX_KERNELS
__attribute__((target("avx"))) void extrapolate_blend_avx(double a, double one_minus_a,
                                                          const double* v, const double* y,
                                                          double* dst, Eigen::Index n) {
  extrapolate_blend<Lanes4, 4>(a, one_minus_a, v, y, dst, n);
}

__attribute__((target("avx"))) void momentum_blend_avx(double b, double one_minus_b, double g,
                                                       const double* v, const double* p,
                                                       const double* y, double* dst,
                                                       Eigen::Index n) {
  momentum_blend<Lanes4, 4>(b, one_minus_b, g, v, p, y, dst, n);
}
#endif

void extrapolate_blend(double a, double one_minus_a, const double* v, const double* y, double* dst,
                       Eigen::Index n) {
#ifdef TESSERA_AVX_KERNELS
  if (avx_kernels_enabled()) return extrapolate_blend_avx(a, one_minus_a, v, y, dst, n);
#endif
  extrapolate_blend<Lanes2, 2>(a, one_minus_a, v, y, dst, n);
}

void momentum_blend(double b, double one_minus_b, double g, const double* v, const double* p,
                    const double* y, double* dst, Eigen::Index n) {
#ifdef TESSERA_AVX_KERNELS
  if (avx_kernels_enabled()) return momentum_blend_avx(b, one_minus_b, g, v, p, y, dst, n);
#endif
  momentum_blend<Lanes2, 2>(b, one_minus_b, g, v, p, y, dst, n);
}

void check_same_shape(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b, const char* what) {
  if (a.rows() != b.rows() || a.cols() != b.cols())
    throw std::invalid_argument(std::string(what) + ": operands of different shapes");
}

}  // namespace

Eigen::MatrixXd project_to_manifold(const LiftedManifold& M, Eigen::MatrixXd X) {
  blend_and_project(M, X, [](Eigen::Index, Eigen::Index, double*) {});
  return X;
}

void extrapolate_into(const LiftedManifold& M, const MomentumCoefficients& c,
                      const Eigen::MatrixXd& Y, const Eigen::MatrixXd& V, Eigen::MatrixXd& out) {
  check_same_shape(Y, V, "extrapolate");
  out.resize(Y.rows(), Y.cols());  // no reallocation when the shape is already right
  const double a = c.alpha, one_minus_a = 1.0 - c.alpha;
  const double* y = Y.data();
  const double* v = V.data();
  blend_and_project(M, out, [&](Eigen::Index at, Eigen::Index n, double* dst) {
    // Element by element the expression alpha V + (1 - alpha) Y of the previous version.
    extrapolate_blend(a, one_minus_a, v + at, y + at, dst, n);
  });
}

void momentum_update_into(const LiftedManifold& M, const MomentumCoefficients& c,
                          const Eigen::MatrixXd& V, const Eigen::MatrixXd& P,
                          const Eigen::MatrixXd& Y_new, Eigen::MatrixXd& out) {
  check_same_shape(V, P, "momentum_update");
  check_same_shape(V, Y_new, "momentum_update");
  out.resize(V.rows(), V.cols());  // a no-op when out is one of the (same-shape) inputs
  const double b = c.beta, one_minus_b = 1.0 - c.beta, g = c.gamma;
  const double* v = V.data();
  const double* p = P.data();
  const double* y = Y_new.data();
  blend_and_project(M, out, [&](Eigen::Index at, Eigen::Index n, double* dst) {
    // (beta V + (1 - beta) P) + gamma (Y_new - P), element by element, as before. dst may be
    // v's pose: each element is read before it is written.
    momentum_blend(b, one_minus_b, g, v + at, p + at, y + at, dst, n);
  });
}

Eigen::MatrixXd extrapolate(const LiftedManifold& M, const MomentumCoefficients& c,
                            const Eigen::MatrixXd& Y, const Eigen::MatrixXd& V) {
  Eigen::MatrixXd out;
  extrapolate_into(M, c, Y, V, out);
  return out;
}

Eigen::MatrixXd momentum_update(const LiftedManifold& M, const MomentumCoefficients& c,
                                const Eigen::MatrixXd& V, const Eigen::MatrixXd& P,
                                const Eigen::MatrixXd& Y_new) {
  Eigen::MatrixXd out;
  momentum_update_into(M, c, V, P, Y_new, out);
  return out;
}

}  // namespace tessera
