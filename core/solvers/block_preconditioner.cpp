#include <Eigen/Cholesky>
#include <Eigen/CholmodSupport>
#include <algorithm>
#include <stdexcept>
#include <tessera/solvers/block_preconditioner.hpp>
#include <vector>

#include "solvers/cholmod_checked.hpp"
#include "util/serial_blas.hpp"

namespace tessera {

struct BlockPreconditioner::Factor {
  // Simplicial LDL^T for small factors. The factor is computed once and solved against
  // thousands of times with only r (= d, mostly) right-hand sides, where the supernodal solve's
  // BLAS calls on small supernodes cost more than they save: measured CPU per solve, simplicial
  // LDL^T vs CHOLMOD's automatic choice (supernodal on these graphs): city10000 2.6 vs 4.8 ms,
  // sphere2500 1.2 vs 2.0 ms, cubicle 5.0 vs 5.9 ms, ais2klinik 0.78 vs 0.72 ms
  // (docs/centralized-solver.md). Supernodal LL^T for large ones (see the constructor).
  // Eigen's wrapper with access to CHOLMOD's factor (to convert it after factorization).
  struct Cholmod : Eigen::CholmodDecomposition<SparseMatrix> {
    cholmod_factor* raw() { return m_cholmodFactor; }
  };
  std::unique_ptr<Cholmod> llt = std::make_unique<Cholmod>();
  bool supernodal = false;
  std::size_t entries = 0;  // the LDL^T analysis' prediction
  double flops = 0.0;
  // Fallback: inverses of the (d+1) x (d+1) diagonal blocks, one after the other (column-major).
  int w = 0;
  std::vector<double> block_inverses;
};

namespace {

// Inverses of the diagonal (w x w) blocks of A (symmetric positive definite blocks).
std::vector<double> diagonal_block_inverses(const SparseMatrix& A, int w) {
  const Eigen::Index blocks = A.rows() / w;
  std::vector<double> out(static_cast<std::size_t>(blocks * w * w));
  Eigen::MatrixXd B(w, w);
  for (Eigen::Index b = 0; b < blocks; ++b) {
    B.setZero();
    for (int c = 0; c < w; ++c)
      for (SparseMatrix::InnerIterator it(A, b * w + c); it; ++it)
        if (it.row() >= b * w && it.row() < (b + 1) * w) B(it.row() - b * w, c) = it.value();
    Eigen::LLT<Eigen::MatrixXd> llt(B);
    if (llt.info() != Eigen::Success)
      throw std::runtime_error("BlockPreconditioner: a diagonal block is not positive definite");
    Eigen::Map<Eigen::MatrixXd>(out.data() + b * w * w, w, w) =
        llt.solve(Eigen::MatrixXd::Identity(w, w));
  }
  return out;
}

}  // namespace

namespace {

// Q_BB + lambda I, lambda = relative_shift * max diagonal entry of Q_BB: the matrix factored.
SparseMatrix shifted_data_matrix(const BlockProblem& problem, double relative_shift) {
  const SparseMatrix& Q = problem.data_matrix();
  const double lambda = relative_shift * std::max(1e-12, Q.diagonal().maxCoeff());
  SparseMatrix A = Q;
  for (Eigen::Index k = 0; k < A.rows(); ++k) A.coeffRef(k, k) += lambda;
  return A;
}

// The factor holds at least the lower triangle of A; beyond that, CHOLMOD's symbolic analysis
// predicts its entries (lnz) before any numeric work.
bool too_large(double entries, std::size_t max_factor_entries) {
  return max_factor_entries > 0 && entries > static_cast<double>(max_factor_entries);
}

bool lower_triangle_too_large(const SparseMatrix& A, std::size_t max_factor_entries) {
  return too_large(0.5 * static_cast<double>(A.nonZeros() + A.rows()), max_factor_entries);
}

// The symbolic analysis of A in `mode`; returns the factor's predicted entries.
template <class Cholmod>
double analyze(Cholmod& llt, const SparseMatrix& A, Eigen::CholmodMode mode,
               bool simplicial_solves) {
  llt.setMode(mode);
  // AMD only. CHOLMOD's default also tries METIS when AMD's fill looks high (it does on 3D
  // grids) and keeps the better one: METIS never won on any block measured (more fill than
  // AMD everywhere, docs/irbcd.md section 8), but its trial was ~2/3 of the set-up time of
  // a 100k-pose grid. The chosen ordering, hence the factor and the iterates, are unchanged.
  cholmod_common& c = llt.cholmod();
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.postorder = 1;
  // A factor to be converted for simplicial solves keeps only fundamental supernodes: the
  // default relaxed amalgamation stores explicit zeros (cubicle: 1.72 M entries instead of
  // 1.45 M) that every simplicial solve would then traverse.
  if (simplicial_solves && mode == Eigen::CholmodSupernodalLLt)
    for (int k = 0; k < 3; ++k) {
      c.nrelax[k] = 0;
      c.zrelax[k] = 0.0;
    }
  llt.analyzePattern(A);
  if (llt.info() != Eigen::Success || cholmod_analysis_failed(llt))
    throw_cholmod_failure("BlockPreconditioner", "analysis", llt.cholmod().status, A.rows(),
                          A.cols());
  return static_cast<double>(llt.cholmod().lnz);
}

}  // namespace

bool BlockPreconditioner::falls_back(const BlockProblem& problem, double relative_shift,
                                     std::size_t max_factor_entries) {
  if (max_factor_entries == 0) return false;
  // Whatever the ordering, the factor of an n x n matrix has at most n (n + 1) / 2 entries: at
  // or below the cap no analysis can find it too large (torus3D's, cubicle's and sphere2500's
  // blocks at N = 5, 4,000-4,600 rows against 5,656 for the default cap; city10000's 2D blocks
  // of ~6,000 rows still take the analysis).
  const double rows = static_cast<double>(problem.data_matrix().rows());
  if (rows * (rows + 1.0) / 2.0 <= static_cast<double>(max_factor_entries)) return false;
  const SparseMatrix A = shifted_data_matrix(problem, relative_shift);
  if (lower_triangle_too_large(A, max_factor_entries)) return true;
  Factor::Cholmod llt;
  return too_large(analyze(llt, A, Eigen::CholmodLDLt, false), max_factor_entries);
}

BlockPreconditioner::BlockPreconditioner(const BlockProblem& problem, double relative_shift,
                                         std::size_t max_factor_entries,
                                         std::size_t supernodal_min_entries,
                                         double supernodal_min_flops, bool simplicial_solves)
    : factor_(std::make_unique<Factor>()) {
  const SparseMatrix A = shifted_data_matrix(problem, relative_shift);
  bool fallback = lower_triangle_too_large(A, max_factor_entries);
  const auto analyze_as = [&](Eigen::CholmodMode mode) {
    factor_->llt = std::make_unique<Factor::Cholmod>();
    return analyze(*factor_->llt, A, mode, simplicial_solves);
  };
  if (!fallback) {
    const double entries = analyze_as(Eigen::CholmodLDLt);
    fallback = too_large(entries, max_factor_entries);
    // A large factor is computed supernodally (dense BLAS-3 kernels on its supernodes): on the
    // 4,000-pose blocks of a 100k-pose 3D grid (1.2-2.0 M entries) set-up CPU drops ~7x and
    // the solves are no slower; at ~0.6 M entries both are equal. The re-analysis repeats the
    // AMD ordering (same permutation), a small part of the factorization. Blocks of all the
    // public benchmark graphs stay below the switch, so their iterates are unchanged.
    // Dense factors (many flops per entry: long-range edges, e.g. wrong loop closures between
    // random poses) likewise: manhattan3500 with 25 % random outliers, 1.1 M entries and
    // 6.9e8 flops, factors in 0.53 s supernodal against 2.0 s simplicial.
    const double flops = factor_->llt->cholmod().fl;
    factor_->entries = static_cast<std::size_t>(entries);
    factor_->flops = flops;
    if (!fallback &&
        ((supernodal_min_entries > 0 && entries > static_cast<double>(supernodal_min_entries)) ||
         (supernodal_min_flops > 0 && flops > supernodal_min_flops)))
      analyze_as(Eigen::CholmodSupernodalLLt);
  }
  if (fallback) {
    factor_->entries = 0;
    factor_->flops = 0.0;
    factor_->llt.reset();  // release the symbolic factor
    factor_->w =
        A.rows() / static_cast<Eigen::Index>(std::max<std::size_t>(1, problem.num_owned()));
    factor_->block_inverses = diagonal_block_inverses(A, factor_->w);
    return;
  }
  if (factor_->llt->raw()->is_super) {  // BLAS on the supernodes
    const SerialBlasLock lock(serial_blas_mutex());
    factor_->llt->factorize(A);
  } else {
    factor_->llt->factorize(A);
  }
  if (factor_->llt->cholmod().status < CHOLMOD_OK)
    throw_cholmod_failure("BlockPreconditioner", "factorization", factor_->llt->cholmod().status,
                          A.rows(), A.cols());
  if (factor_->llt->info() != Eigen::Success)
    throw std::runtime_error(
        "BlockPreconditioner: the block's data matrix is not positive definite (its Cholesky "
        "factorization stopped at column " +
        std::to_string(factor_->llt->raw()->minor) + " of " + std::to_string(A.rows()) + ")");
  factor_->supernodal = factor_->llt->cholmod().supernodal == CHOLMOD_SUPERNODAL;
  // The supernodal solve's BLAS calls on small supernodes cost more than they save with a few
  // right-hand sides: the factor is converted to the simplicial LDL^T form, whose solves cost
  // what the simplicial factorization's do (cubicle: 779 M instructions for 20 solves either
  // way), while the factorization drops from 1.26 G to 0.46 G instructions.
  if (factor_->supernodal && simplicial_solves &&
      !cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/0, /*to_super=*/0, /*to_packed=*/1,
                             /*to_monotonic=*/1, factor_->llt->raw(), &factor_->llt->cholmod()))
    throw_cholmod_failure("BlockPreconditioner", "factor conversion",
                          factor_->llt->cholmod().status, A.rows(), A.cols());
}

bool BlockPreconditioner::block_diagonal() const {
  return factor_->w > 0;
}

bool BlockPreconditioner::supernodal() const {
  return factor_->w == 0 && factor_->supernodal;
}

std::size_t BlockPreconditioner::factor_entries() const {
  return factor_->entries;
}

double BlockPreconditioner::factor_flops() const {
  return factor_->flops;
}

BlockPreconditioner::~BlockPreconditioner() = default;

Eigen::MatrixXd BlockPreconditioner::apply(const LiftedManifold& manifold, const Eigen::MatrixXd& X,
                                           const Eigen::MatrixXd& V) const {
  if (factor_->w > 0) {
    // Rows of V times the symmetric block inverses, pose by pose.
    const Eigen::Index w = factor_->w, blocks = V.cols() / w;
    Eigen::MatrixXd Z(V.rows(), V.cols());
    for (Eigen::Index b = 0; b < blocks; ++b)
      Z.middleCols(b * w, w).noalias() =
          V.middleCols(b * w, w) *
          Eigen::Map<const Eigen::MatrixXd>(factor_->block_inverses.data() + b * w * w, w, w);
    return manifold.tangent_project(X, 0.5 * Z);
  }
  Eigen::MatrixXd Vt = V.transpose();
  Eigen::MatrixXd Z;
  if (factor_->llt->raw()->is_super) {  // not converted: BLAS on the supernodes
    const SerialBlasLock lock(serial_blas_mutex());
    Z = factor_->llt->solve(Vt).transpose();
  } else {
    Z = factor_->llt->solve(Vt).transpose();
  }
  return manifold.tangent_project(X, 0.5 * Z);
}

}  // namespace tessera
