#pragma once
// What the certificate proves at ANY point Y, critical or not: a lower bound on the optimum by
// weak duality, and from it a bound on how far Y (or the rounded estimate) is from the optimum.
//
// With Lambda = Lambda(Y) (certificate.hpp: SymBlockDiag of Y_i^T (Y Q)_i on the rotation
// blocks, zero on translations) and S = Q - Lambda, every feasible Z of the SDP relaxation
// (Z >= 0, identity d x d rotation blocks; its translation gauge fixed so that pose 0's
// translation is zero, which leaves tr(Q Z) unchanged) has
//   tr(Q Z) = tr(S Z) + tr(Lambda Z) = tr(S Z) + tr(Lambda).
// If S + D is positive definite, D diagonal with s_i on pose i's d rotation coordinates, any
// positive value on pose 0's translation coordinate and zero on the other translations, then
// tr(S Z) >= -tr(D Z) = -d sum_i s_i. Hence, for the optimum f* of the relaxation and so of
// pose-graph optimization,
//   f* >= f_lb = tr(Lambda) - d sum_i s_i = tr(Lambda) - s n d,   s = the mean of the s_i,
// in the objective convention of Q (the full sum over the measurements; f(Y) = tr(Q Y^T Y)).
// The translations need the anchor, not a shift: a shift on every translation would add its
// size times the sum of the squared (unknown) optimal translations.
//
// Which D: at a first-order critical point tr(Lambda) = f(Y) and S >= 0, so a uniform floor
// s_i = s0 proves f_lb = f(Y) - s0 n d. Short of it, Lambda is off by about the gradient, and
// mostly where the gradient is: the negative curvature of S is local, about
// ||(Y S)_i||^2 / k_i at pose i (k_i: the mean rotation diagonal of Q_ii, the pose's stiffness).
// So s_i = s0 + alpha ||(Y S)_i||^2 / k_i: a uniform shift would have to cover the worst pose
// at every pose (an RBCD iterate on parking-garage at ||grad f|| = 1e-4 proved 0.0127 above
// f(Y) with a uniform shift). The proof's ladder is D(t): (s0, alpha) = (t s0, t) with s0 =
// first_proof_shift. It tries t = 1 (a bound a tenth of the tolerance), then at once the
// largest t whose bound still certifies (largest_certifying_multiplier): S + D(t) > 0 is
// monotone in t, so that one factorization decides whether any rung certifies (cubicle's
// IRBCD point at |grad f| 0.009 failed at t = 1 and 3 and passed at 9, over the tolerance; it
// passes at t_max = 6.9). Only a point that fails there goes on up by kProofShiftGrowth, for
// a proved bound that does not certify.
//
// The proof is a factorization of S + D (centralized: CHOLMOD; distributed: the exact
// interface test of interface_schur.hpp), never an eigenvalue estimate. `certified` means
// (f(Y) - f_lb) <= suboptimality_tolerance * max(1, |f(Y)|).

#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <tessera/problem/data_matrix.hpp>
#include <vector>

namespace tessera {

/// Default relative bound on (f(Y) - f_lb) / max(1, |f(Y)|) for `certified` (the same
/// normalisation as the rounding gap, rounding_gap.hpp). Why 1e-4, not tighter: the smallest
/// floor a factorization can prove is about 1e-13 max diag Q (round-off), and its cost
/// 1e-13 max diag Q n d is 2.6e-5 of f* on kitti_02 (max diag Q 3.1e6, f* 108, n d 9,322); the
/// distributed interface test needed 3x that floor there (2.6e-5 -> 7.9e-5).
inline constexpr double kDefaultSuboptimalityTolerance = 1e-4;

/// The factor by which the proof's floor s0 and alpha grow after a failed factorization.
inline constexpr double kProofShiftGrowth = 3.0;

/// What decided `certified`.
enum class CertificateMethod {
  kNone,    ///< No certificate ran.
  kExact,   ///< A factorization of S + D (centralized, or the distributed interface test):
            ///< the bound is proved.
  kLobpcg,  ///< The distributed certificate without the interface test: LOBPCG's converged
            ///< lambda_min(S) >= -eta at a point whose |grad f| <= suboptimality_tolerance *
            ///< max(1, |f|), SE-Sync's standard (an estimate at a critical point); no bound proved.
};

/// "exact", "lobpcg", or "none".
const char* certificate_method_name(CertificateMethod m);

struct DualBound {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  CertificateMethod method = CertificateMethod::kNone;
  double relaxation_cost = kNaN;  ///< f(Y) = tr(Q Y^T Y).
  double trace_lambda = kNaN;     ///< tr(Lambda(Y)); equals f(Y) at a critical point.
  double gradient_norm = kNaN;    ///< |grad f(Y)| (Riemannian) = 2 ||Y S||_F.
  /// The mean s of the per-pose shifts s_i of the proved S + D > 0; NaN when no
  /// factorization proved one (then there is no bound: lower_bound is NaN).
  double shift = kNaN;
  double lower_bound = kNaN;  ///< f_lb = trace_lambda - shift n d; NaN when unproved.

  bool proved() const { return lower_bound == lower_bound; }
  /// cost - f_lb: how far an estimate of cost `cost` can be above the optimum (NaN unproved).
  double suboptimality(double cost) const { return cost - lower_bound; }
  /// suboptimality(cost) / max(1, |f(Y)|).
  double relative_suboptimality(double cost) const;
};

/// f_lb from its parts: `shift_sum` = sum_i s_i over the n = `poses` poses, `d` the dimension;
/// NaN shift_sum: unproved.
DualBound make_dual_bound(double relaxation_cost, double trace_lambda, double gradient_norm,
                          double shift_sum, std::size_t poses, int d);

/// The first floor s0: small enough that s0 n d costs a tenth of the tolerance,
/// 0.1 * tolerance * max(1, |f(Y)|) / (n d), and at least 1e-13 * scale (below that the
/// factorization of S + D reads round-off of S's entries of size `scale` as the verdict).
double first_proof_shift(double relaxation_cost, std::size_t poses, int d, double tolerance,
                         double scale);

/// The proof ladder's largest multiplier t that certifies: f(Y) - f_lb for D(t) is
/// (f(Y) - tr(Lambda)) + d t (s0 n + sum_i w_i) (`weight_sum` = sum_i w_i over the n = `poses`
/// poses), at most kCertifyingMargin * tolerance * max(1, |f(Y)|). <= 0 when none does (f(Y) -
/// tr(Lambda), the translations' share of the gradient, uses the whole tolerance).
double largest_certifying_multiplier(double relaxation_cost, double trace_lambda, double s0,
                                     double weight_sum, std::size_t poses, int d, double tolerance);

/// The share of the tolerance largest_certifying_multiplier spends: the bound's sums round.
inline constexpr double kCertifyingMargin = 0.99;

/// The bound's verdict: proved and (f(Y) - f_lb) <= tolerance * max(1, |f(Y)|).
bool bound_certifies(const DualBound& bound, double tolerance);

/// w_i = ||(Y S)_i||_F^2 / k_i for each pose of a block (see above): `YS` is (Y S) on the
/// block's (d+1) m coordinates, `Q` the block's data matrix (its diagonal gives k_i).
std::vector<double> proof_shift_weights(const Eigen::MatrixXd& YS, const SparseMatrix& Q, int d);

/// D on a block's coordinates (pose-major, (d+1) a pose): s0 + alpha w_i on pose i's rotation
/// coordinates, s0 on global pose 0's translation, 0 on the other translations. `poses` are
/// the block's global ids in its coordinate order.
Eigen::VectorXd proof_shift_diagonal(const std::vector<std::size_t>& poses, int d,
                                     const std::vector<double>& weights, double s0, double alpha);

}  // namespace tessera
