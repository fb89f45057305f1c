#include <Spectra/SymEigsSolver.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <tessera/certification/certificate.hpp>
#include <tessera/util/input_error.hpp>

#include "certification/certificate_factor.hpp"
#include "certification/row_space_ritz.hpp"

namespace tessera {

void CertificateOptions::validate() const {
  if (!(relative_tolerance >= 0))
    throw InputError("CertificateOptions.relative_tolerance must be >= 0");
  if (lanczos_max_iterations <= 0)
    throw InputError("CertificateOptions.lanczos_max_iterations must be > 0");
  if (!(lanczos_tolerance > 0))
    throw InputError("CertificateOptions.lanczos_tolerance must be > 0");
  if (lanczos_subspace < 3 || lanczos_subspace > 1000)
    throw InputError("CertificateOptions.lanczos_subspace must be in [3, 1000]");
  if (certified_lanczos_subspace < 3 || certified_lanczos_subspace > 1000)
    throw InputError("CertificateOptions.certified_lanczos_subspace must be in [3, 1000]");
  if (!(suboptimality_tolerance >= 0))
    throw InputError("CertificateOptions.suboptimality_tolerance must be >= 0");
}

SparseMatrix certificate_matrix(const BlockProblem& problem, const Eigen::MatrixXd& X) {
  const int d = problem.dim();
  const SparseMatrix& Q = problem.data_matrix();
  Eigen::MatrixXd G = X * Q;  // half the Euclidean gradient
  const Eigen::Index n = static_cast<Eigen::Index>(problem.num_owned());
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(n * d * d));
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index c = (d + 1) * i;
    Eigen::MatrixXd L = X.middleCols(c, d).transpose() * G.middleCols(c, d);
    L = (0.5 * (L + L.transpose())).eval();  // eval: transpose aliases L
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) trip.emplace_back(c + a, c + b, -L(a, b));
  }
  SparseMatrix Lambda(Q.rows(), Q.cols());
  Lambda.setFromTriplets(trip.begin(), trip.end());
  SparseMatrix S = Q + Lambda;
  S.makeCompressed();
  return S;
}

namespace {

// y = (S + shift I)^{-1} x through the certificate's factor, for Spectra.
class ShiftInvertOp {
 public:
  using Scalar = double;
  explicit ShiftInvertOp(const CertificateFactor& f) : factor_(f) {}
  Eigen::Index rows() const { return factor_.rows(); }
  Eigen::Index cols() const { return factor_.rows(); }
  void perform_op(const double* x_in, double* y_out) const { factor_.solve(x_in, y_out); }

 private:
  const CertificateFactor& factor_;
};

// Largest eigenvalue of (S + shift I)^{-1}: 1/(lambda_min + shift). Returns lambda_min.
// `start`: the Lanczos start vector, or null for Spectra's random one.
double min_eigen_by_shift_invert(const CertificateFactor& factor, double shift,
                                 const CertificateOptions& opt, int subspace,
                                 const Eigen::VectorXd* start, Eigen::VectorXd* vec,
                                 CertificateResult* counts) {
  ShiftInvertOp op(factor);
  const Eigen::Index ncv = std::min<Eigen::Index>(factor.rows(), subspace);
  Spectra::SymEigsSolver<ShiftInvertOp> eigs(op, 1, ncv);
  if (start)
    eigs.init(start->data());
  else
    eigs.init();
  eigs.compute(Spectra::SortRule::LargestAlge, opt.lanczos_max_iterations, opt.lanczos_tolerance);
  counts->lanczos_iterations += static_cast<int>(eigs.num_iterations());
  counts->lanczos_solves += static_cast<int>(eigs.num_operations());
  if (eigs.info() != Spectra::CompInfo::Successful) return std::numeric_limits<double>::quiet_NaN();
  const double nu = eigs.eigenvalues()(0);
  if (vec) *vec = eigs.eigenvectors().col(0);
  return 1.0 / nu - shift;
}

}  // namespace

CertificateResult verify_certificate(const BlockProblem& problem, const Eigen::MatrixXd& X,
                                     const CertificateOptions& options) {
  options.validate();
  if (problem.num_neighbors() != 0)
    throw std::invalid_argument("verify_certificate: needs the centralized problem");
  const auto start = std::chrono::steady_clock::now();
  CertificateResult res;
  const SparseMatrix S = certificate_matrix(problem, X);
  const Eigen::Index n = S.rows();
  const int d = problem.dim();
  const std::size_t poses = problem.num_owned();
  const SparseMatrix& Q = problem.data_matrix();
  const double scale = std::max(1.0, Q.diagonal().maxCoeff());
  res.tolerance = options.relative_tolerance * scale;
  // One symbolic analysis for every factorization below (they differ on the diagonal only).
  CertificateFactor factor(S, d + 1);
  auto factor_shifted = [&](const Eigen::VectorXd& D) {
    ++res.factorizations;
    return factor.factor(S, D);
  };

  // The weak-duality bound (dual_bound.hpp), proved by factoring S + D(t) on the proof's
  // ladder: t = 1 (a bound a tenth of the tolerance), else the largest t that certifies.
  const Eigen::MatrixXd XS = X * S;
  const double f = (X * Q).cwiseProduct(X).sum();
  const double trace_lambda = (Q.diagonal() - S.diagonal()).sum();
  const double floor = first_proof_shift(f, poses, d, options.suboptimality_tolerance, scale);
  const std::vector<double> w = proof_shift_weights(XS, Q, d);
  const double weight_sum = std::accumulate(w.begin(), w.end(), 0.0);
  auto proof_diagonal = [&](double s, double alpha) {
    return proof_shift_diagonal(problem.owned(), d, w, s, alpha);
  };
  double proved = std::numeric_limits<double>::quiet_NaN();  // sum_i s_i of the proof
  double proved_max_shift = 0.0;                             // max_i s_i
  auto prove = [&](double s, double alpha) {
    const Eigen::VectorXd D = proof_diagonal(s, alpha);
    ++res.proof_factorizations;
    if (!factor_shifted(D)) return false;
    proved = s * static_cast<double>(poses) + alpha * weight_sum;
    proved_max_shift = D.maxCoeff();
    return true;
  };
  const double largest = largest_certifying_multiplier(f, trace_lambda, floor, weight_sum, poses, d,
                                                       options.suboptimality_tolerance);
  const bool at_floor = prove(floor, 1.0);
  const bool at_largest = !at_floor && largest > 1.0 && prove(largest * floor, largest);

  // The saddle test, S + eta I > 0 (a tiny floor keeps the shift-invert operator defined when
  // eta is 0), and lambda_min. A proof with every s_i <= eta has passed it already: S + eta I
  // >= S + D > 0. Then lambda_min lies in (-max_i s_i, theta], theta the smallest Ritz value on
  // X's rows (S's null space at a critical point); where that bracket is narrower than eta,
  // theta is reported without a factorization of its own or a Lanczos run.
  double shift = std::max(res.tolerance, 1e-12 * scale);
  bool psd = false;
  bool reported = false;
  if ((at_floor || at_largest) && proved_max_shift <= shift) {
    psd = true;
    const RowSpaceRitz ritz =
        row_space_ritz(X * X.transpose(), XS * X.transpose(), XS * XS.transpose());
    if (std::isfinite(ritz.theta) && ritz.theta + proved_max_shift <= shift) {
      res.min_eigenvalue = ritz.theta;
      reported = true;
    }
  }
  Eigen::VectorXd v;
  if (!reported) {
    psd = factor_shifted(Eigen::VectorXd::Constant(n, shift));
    // Not PSD within eta: push the shift down (S + shift I is PD for shift > -lambda_min,
    // and -lambda_min <= the Gershgorin radius) until the factorization exists.
    for (bool ok = psd; !ok;) {
      shift *= 10.0;
      if (shift > 1e3 * scale * 4) throw std::runtime_error("certificate: no PD shift found");
      ok = factor_shifted(Eigen::VectorXd::Constant(n, shift));
    }
    if (psd) {
      // Only reported: start from X's rows, (about) S's null space at a critical point.
      Eigen::VectorXd start_vector = X.colwise().sum().transpose();
      const double norm = start_vector.norm();
      const bool usable = std::isfinite(norm) && norm > 0;
      if (usable) start_vector /= norm;
      res.min_eigenvalue =
          min_eigen_by_shift_invert(factor, shift, options, options.certified_lanczos_subspace,
                                    usable ? &start_vector : nullptr, nullptr, &res);
      // The narrow space can miss where the top of the inverted spectrum is a tight cluster
      // (S's null space at a point refined far below the solver's tolerance): the wide one.
      if (!std::isfinite(res.min_eigenvalue))
        res.min_eigenvalue = min_eigen_by_shift_invert(
            factor, shift, options, options.lanczos_subspace, nullptr, nullptr, &res);
    } else {
      res.min_eigenvalue = min_eigen_by_shift_invert(factor, shift, options,
                                                     options.lanczos_subspace, nullptr, &v, &res);
      // The search shift can be far above -lambda_min, leaving lambda_min poorly separated in
      // the inverted spectrum (an inaccurate eigenvector). Move the shift just past the
      // estimate and solve again; keep the first answer if that shift is not PD after all.
      const double tight = -res.min_eigenvalue + 1e-2 * std::abs(res.min_eigenvalue);
      if (std::isfinite(tight) && tight < shift &&
          factor_shifted(Eigen::VectorXd::Constant(n, tight)))
        res.min_eigenvalue = min_eigen_by_shift_invert(factor, tight, options,
                                                       options.lanczos_subspace, nullptr, &v, &res);
    }
  }
  if (!psd && v.size() > 0) res.min_eigenvector = v.normalized();
  // The factorization test is the authority; the eigenvalue estimate agrees with it up to
  // Lanczos accuracy.
  res.psd_within_tolerance = psd;

  // No rung up to the largest certifying one passed: on up the ladder for a proved bound that
  // does not certify. lambda_min(S) >= the rotation Schur complement's lambda_min, so
  // -lambda_min(S) is where a saddle's proof can start.
  if (!at_floor && !at_largest) {
    double s = floor, alpha = 1.0;
    if (!psd && std::isfinite(res.min_eigenvalue) && -1.01 * res.min_eigenvalue > floor) {
      s = -1.01 * res.min_eigenvalue;
    } else {
      while (alpha <= std::max(1.0, largest)) alpha *= kProofShiftGrowth;
      s = alpha * floor;
    }
    for (; s <= 4e3 * scale; s *= kProofShiftGrowth, alpha *= kProofShiftGrowth)
      if (prove(s, alpha)) break;
  }
  res.bound = make_dual_bound(f, trace_lambda, 2.0 * XS.norm(), proved, poses, d);
  // The bound is the proof; S + eta I > 0 alone is not (it holds short of a critical point).
  res.certified = bound_certifies(res.bound, options.suboptimality_tolerance);
  res.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

}  // namespace tessera
