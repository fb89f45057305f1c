#include <Spectra/SymEigsSolver.h>

#include <Eigen/CholmodSupport>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <tessera/certification/certificate.hpp>
#include <tessera/util/input_error.hpp>

#include "solvers/cholmod_checked.hpp"

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

// LL^T: its failure on a non-PD matrix is the test. CHOLMOD chooses simplicial or supernodal
// from the factor's flop count per entry: supernodal (dense kernels) on the 3D graphs, where the
// simplicial factorization was half of the certificate's time (torus3D, cubicle, sphere2500:
// certificate 1.5-2x faster), simplicial on the 2D ones, where it stays the faster.
using Factor = Eigen::CholmodDecomposition<SparseMatrix>;

// y = (S - sigma I)^{-1} x through a Cholesky factor, for Spectra.
class ShiftInvertOp {
 public:
  using Scalar = double;
  explicit ShiftInvertOp(const Factor& f, Eigen::Index n) : factor_(f), n_(n) {}
  Eigen::Index rows() const { return n_; }
  Eigen::Index cols() const { return n_; }
  void perform_op(const double* x_in, double* y_out) const {
    Eigen::Map<const Eigen::VectorXd> x(x_in, n_);
    Eigen::Map<Eigen::VectorXd> y(y_out, n_);
    y = factor_.solve(x);
  }

 private:
  const Factor& factor_;
  Eigen::Index n_;
};

// A failed factorization is an expected outcome here (it is the test), so CHOLMOD must not
// print its "not positive definite" warning.
void quiet(Factor& f) {
  f.cholmod().print = 0;
  f.setMode(Eigen::CholmodAuto);
  // LL^T in the simplicial case too: LDL^T (CHOLMOD's simplicial default) exists for indefinite
  // matrices, so it would pass every test.
  f.cholmod().final_ll = 1;
}

// S + diag(D): the proof's per-coordinate shift (dual_bound.hpp), or a uniform one.
SparseMatrix proof_shifted(const SparseMatrix& S, const Eigen::VectorXd& D) {
  SparseMatrix A = S;
  for (Eigen::Index k = 0; k < A.rows(); ++k)
    if (D(k) != 0.0) A.coeffRef(k, k) += D(k);
  return A;
}

SparseMatrix shifted(const SparseMatrix& S, double shift) {
  return proof_shifted(S, Eigen::VectorXd::Constant(S.rows(), shift));
}

// Largest eigenvalue of (S + shift I)^{-1}: 1/(lambda_min + shift). Returns lambda_min.
// `start`: the Lanczos start vector, or null for Spectra's random one.
double min_eigen_by_shift_invert(const Factor& factor, Eigen::Index n, double shift,
                                 const CertificateOptions& opt, int subspace,
                                 const Eigen::VectorXd* start, Eigen::VectorXd* vec,
                                 CertificateResult* counts) {
  ShiftInvertOp op(factor, n);
  const Eigen::Index ncv = std::min<Eigen::Index>(n, subspace);
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
  const double scale = std::max(1.0, problem.data_matrix().diagonal().maxCoeff());
  res.tolerance = options.relative_tolerance * scale;
  // A tiny floor keeps the shift-invert operator defined when eta is 0.
  double shift = std::max(res.tolerance, 1e-12 * scale);
  Factor factor;
  quiet(factor);
  cholmod_compute_checked(factor, shifted(S, shift), "certificate");
  ++res.factorizations;
  res.certified = factor.info() == Eigen::Success;
  // Not PSD within eta: push the shift down (S + shift I is PD for shift > -lambda_min,
  // and -lambda_min <= the Gershgorin radius) until the factorization exists.
  while (factor.info() != Eigen::Success) {
    shift *= 10.0;
    if (shift > 1e3 * scale * 4) throw std::runtime_error("certificate: no PD shift found");
    cholmod_compute_checked(factor, shifted(S, shift), "certificate");
    ++res.factorizations;
  }
  Eigen::VectorXd v;
  if (res.certified) {
    // Only reported: start from X's rows, (about) S's null space at a critical point.
    Eigen::VectorXd start = X.colwise().sum().transpose();
    const double norm = start.norm();
    const bool usable = std::isfinite(norm) && norm > 0;
    if (usable) start /= norm;
    res.min_eigenvalue =
        min_eigen_by_shift_invert(factor, n, shift, options, options.certified_lanczos_subspace,
                                  usable ? &start : nullptr, nullptr, &res);
    // The narrow space can miss where the top of the inverted spectrum is a tight cluster
    // (S's null space at a point refined far below the solver's tolerance): the wide one.
    if (!std::isfinite(res.min_eigenvalue))
      res.min_eigenvalue = min_eigen_by_shift_invert(
          factor, n, shift, options, options.lanczos_subspace, nullptr, nullptr, &res);
  } else {
    res.min_eigenvalue = min_eigen_by_shift_invert(factor, n, shift, options,
                                                   options.lanczos_subspace, nullptr, &v, &res);
  }
  if (!res.certified) {
    // The search shift can be far above -lambda_min, leaving lambda_min poorly separated in
    // the inverted spectrum (an inaccurate eigenvector). Move the shift just past the
    // estimate and solve again; keep the first answer if that shift is not PD after all.
    const double tight = -res.min_eigenvalue + 1e-2 * std::abs(res.min_eigenvalue);
    if (std::isfinite(tight) && tight < shift) {
      Factor refined;
      quiet(refined);
      cholmod_compute_checked(refined, shifted(S, tight), "certificate");
      ++res.factorizations;
      if (refined.info() == Eigen::Success)
        res.min_eigenvalue = min_eigen_by_shift_invert(refined, n, tight, options,
                                                       options.lanczos_subspace, nullptr, &v, &res);
    }
  }
  if (!res.certified && v.size() > 0) res.min_eigenvector = v.normalized();
  // The factorization test is the authority; the eigenvalue estimate agrees with it up to
  // Lanczos accuracy.
  res.psd_within_tolerance = res.certified;

  // The weak-duality bound (dual_bound.hpp), proved by factoring S + D from the smallest floor
  // that would certify up by factors of kProofShiftGrowth. lambda_min(S) >= the rotation Schur
  // complement's lambda_min, so -lambda_min(S) is where a saddle's proof can start.
  const int d = problem.dim();
  const std::size_t poses = problem.num_owned();
  const SparseMatrix& Q = problem.data_matrix();
  const Eigen::MatrixXd XS = X * S;
  const double f = (X * Q).cwiseProduct(X).sum();
  const double trace_lambda = (Q.diagonal() - S.diagonal()).sum();
  double s = first_proof_shift(f, poses, d, options.suboptimality_tolerance, scale);
  if (!res.psd_within_tolerance && std::isfinite(res.min_eigenvalue))
    s = std::max(s, -1.01 * res.min_eigenvalue);
  const std::vector<double> w = proof_shift_weights(XS, Q, d);
  const double weight_sum = std::accumulate(w.begin(), w.end(), 0.0);
  double proved = std::numeric_limits<double>::quiet_NaN();
  for (double alpha = 1.0; s <= 4e3 * scale; s *= kProofShiftGrowth, alpha *= kProofShiftGrowth) {
    Factor proof;
    quiet(proof);
    cholmod_compute_checked(proof,
                            proof_shifted(S, proof_shift_diagonal(problem.owned(), d, w, s, alpha)),
                            "certificate bound");
    ++res.factorizations;
    ++res.proof_factorizations;
    if (proof.info() == Eigen::Success) {
      proved = s * static_cast<double>(poses) + alpha * weight_sum;
      break;
    }
  }
  res.bound = make_dual_bound(f, trace_lambda, 2.0 * XS.norm(), proved, poses, d);
  // The bound is the proof; S + eta I > 0 alone is not (it holds short of a critical point).
  res.certified = bound_certifies(res.bound, options.suboptimality_tolerance);
  res.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

}  // namespace tessera
