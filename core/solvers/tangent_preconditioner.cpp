#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <stdexcept>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <vector>

#include "solvers/cholmod_checked.hpp"
#include "solvers/pose_level_analysis.hpp"
#include "solvers/tangent_coordinates.hpp"
#include "solvers/tangent_factor.hpp"
#include "util/serial_blas.hpp"

namespace tessera {

namespace {

// The pose-level estimate is skipped to the exact analysis below this multiple of the cap,
// so that a factor near the cap is decided by its exact size as before.
constexpr double kSkipFactor = 2.0;

// Entries of A's LDL^T factor estimated from the pose-level pattern (`rows`: the row blocks of
// each block column, diagonal included): the pose-level factor's entries (same AMD ordering,
// symbolic only), each off-diagonal block p x p dense and each diagonal block triangular.
// `order` (when not null) receives the pose-level analysis' ordering (CHOLMOD's Perm, postordered),
// `flops` (when not null) p^3 times the pose-level factorization's flops: an estimate of A's,
// which counts each column's entries squared (0 without an estimate).
double pose_level_fill_estimate(const std::vector<std::vector<Eigen::Index>>& rows, int p,
                                std::vector<int>* order = nullptr, double* flops = nullptr) {
  const Eigen::Index m = static_cast<Eigen::Index>(rows.size());
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index i : rows[static_cast<std::size_t>(j)])
      t.emplace_back(i, j, i == j ? static_cast<double>(m) : 1.0);
  SparseMatrix B(m, m);
  B.setFromTriplets(t.begin(), t.end());
  const PoseLevelAnalysis a = analyse_pose_level_pattern(B, order != nullptr);
  if (!a.ok) return 0.0;  // no estimate: the exact analysis decides
  if (order) *order = a.order;
  if (flops) *flops = a.flops * p * p * p;
  const double md = static_cast<double>(m), block_entries = a.factor_entries;
  return (block_entries - md) * p * p + md * p * (p + 1) / 2.0;
}

}  // namespace

TangentPreconditioner::TangentPreconditioner(const BlockProblem& problem, double relative_shift,
                                             std::size_t max_factor_entries,
                                             double supernodal_min_flops, bool simplicial_solves)
    : factor_(std::make_unique<Factor>()) {
  if (!(relative_shift >= 0))
    throw std::invalid_argument("TangentPreconditioner: relative_shift must be >= 0");
  Factor& f = *factor_;
  f.d = problem.dim();
  f.p = f.d * (f.d + 1) / 2;
  f.m = static_cast<Eigen::Index>(problem.num_owned());
  f.relative_shift = relative_shift;
  const int w = f.d + 1;
  // What only the factor needs goes when it is not usable, not with the preconditioner.
  const auto release_factor_inputs = [&f] {
    f.A = SparseMatrix();
    std::vector<double>().swap(f.q_blocks);
    std::vector<Eigen::Index>().swap(f.block_row);
    std::vector<Eigen::Index>().swap(f.block_start);
    std::vector<Eigen::Index>().swap(f.diagonal_slot);
  };
  SparseMatrix Q = problem.data_matrix();
  Q.makeCompressed();

  // Pose-block pattern of Q (row blocks per block column).
  std::vector<std::vector<Eigen::Index>> rows(static_cast<std::size_t>(f.m));
  for (Eigen::Index j = 0; j < f.m; ++j) {
    auto& r = rows[static_cast<std::size_t>(j)];
    r.push_back(j);
    for (int s = 0; s < w; ++s)
      for (SparseMatrix::InnerIterator it(Q, j * w + s); it; ++it) r.push_back(it.row() / w);
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  // A factor far over the cap is known from the pose-level pattern alone (m x m, p^2 times
  // smaller than A's): then A is never built. On a 40,000-pose block of a 3D grid, A's
  // pattern and Q's dense blocks alone were ~300 MB per agent, for a factor never used.
  // Its ordering, each pose's p coordinates kept together, is A's: AMD on A itself found the
  // same blocks (p coordinates per pose) at p^2 times the work.
  std::vector<int> pose_order;
  double flops_estimate = 0.0;
  {
    const double estimate = pose_level_fill_estimate(rows, f.p, &pose_order, &flops_estimate);
    if (max_factor_entries > 0 &&
        estimate > kSkipFactor * static_cast<double>(max_factor_entries)) {
      f.entries = static_cast<std::size_t>(estimate);
      return;  // not usable
    }
  }
  f.block_start.assign(1, 0);
  for (Eigen::Index j = 0; j < f.m; ++j) {
    const auto& r = rows[static_cast<std::size_t>(j)];
    f.diagonal_slot.push_back(f.block_start.back() +
                              (std::lower_bound(r.begin(), r.end(), j) - r.begin()));
    f.block_row.insert(f.block_row.end(), r.begin(), r.end());
    f.block_start.push_back(static_cast<Eigen::Index>(f.block_row.size()));
  }
  // Q's pose blocks, densely.
  f.q_blocks.assign(f.block_row.size() * static_cast<std::size_t>(w * w), 0.0);
  for (Eigen::Index j = 0; j < f.m; ++j) {
    const auto begin = f.block_row.begin() + f.block_start[static_cast<std::size_t>(j)];
    const auto end = f.block_row.begin() + f.block_start[static_cast<std::size_t>(j) + 1];
    for (int s = 0; s < w; ++s)
      for (SparseMatrix::InnerIterator it(Q, j * w + s); it; ++it) {
        const Eigen::Index slot = std::lower_bound(begin, end, it.row() / w) - f.block_row.begin();
        f.q_blocks[static_cast<std::size_t>(slot * w * w + s * w + it.row() % w)] = it.value();
      }
  }
  // A's pattern, lower block triangle only: block column j's columns each hold p rows per row
  // block i >= j. CHOLMOD reads A's lower half only, and every analysis and factorization
  // transposes the whole stored pattern: the blocks above the diagonal were half of that work
  // (and of A's memory) for entries never read.
  const Eigen::Index n = f.m * f.p;
  Eigen::Index lower_blocks = 0;
  for (Eigen::Index j = 0; j < f.m; ++j)
    lower_blocks += f.block_start[static_cast<std::size_t>(j) + 1] -
                    f.diagonal_slot[static_cast<std::size_t>(j)];
  const Eigen::Index nnz = lower_blocks * f.p * f.p;
  f.A.resize(n, n);
  f.A.resizeNonZeros(nnz);
  Eigen::Index pos = 0;
  for (Eigen::Index j = 0; j < f.m; ++j)
    for (int c = 0; c < f.p; ++c) {
      f.A.outerIndexPtr()[j * f.p + c] = static_cast<int>(pos);
      for (Eigen::Index s = f.diagonal_slot[static_cast<std::size_t>(j)];
           s < f.block_start[static_cast<std::size_t>(j) + 1]; ++s)
        for (int r = 0; r < f.p; ++r) {
          f.A.innerIndexPtr()[pos] =
              static_cast<int>(f.block_row[static_cast<std::size_t>(s)] * f.p + r);
          f.A.valuePtr()[pos] = 0.0;
          ++pos;
        }
    }
  f.A.outerIndexPtr()[n] = static_cast<int>(pos);

  // A factorization far above supernodal_min_flops by the pose-level estimate goes to the
  // supernodal analysis at once (no simplicial analysis only to learn its size); near the
  // threshold the simplicial analysis decides.
  std::vector<int> order;
  if (f.m > 0 && pose_order.size() == static_cast<std::size_t>(f.m))
    order = coordinate_order(pose_order, f.p);
  if (simplicial_solves && supernodal_min_flops > 0 && !order.empty() &&
      flops_estimate > kSkipFactor * supernodal_min_flops) {
    f.order = std::move(order);
    f.convert = true;
    if (!f.analyze_supernodal()) return;  // not usable
    f.entries = static_cast<std::size_t>(f.llt.cholmod().lnz);
    f.flops = f.llt.cholmod().fl;
    f.usable = max_factor_entries == 0 || f.entries <= max_factor_entries;
    if (!f.usable) release_factor_inputs();
    return;
  }
  // Symbolic analysis once (the pose-level AMD ordering above, else AMD; simplicial LDL^T:
  // supernodal LL^T took 6 % more instructions on the online steps of a 1,000-pose grid).
  f.llt.setMode(Eigen::CholmodLDLt);
  cholmod_common& c = f.llt.cholmod();
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.postorder = 1;
  if (!order.empty()) {
    f.llt.analyze_with_ordering(f.A, order);
  } else {
    f.llt.analyzePattern(f.A);
  }
  if (f.llt.info() != Eigen::Success || cholmod_analysis_failed(f.llt)) return;  // not usable
  f.entries = static_cast<std::size_t>(f.llt.cholmod().lnz);
  f.flops = f.llt.cholmod().fl;
  // A dense factorization (3D graphs: p = 6 coordinates a pose, (6/4)^3 the flops of the
  // Euclidean factor of Q) is several times cheaper with BLAS on its supernodes. The re-analysis
  // repeats the AMD ordering, a small part of such a factorization.
  if (supernodal_min_flops > 0 && f.flops > supernodal_min_flops && simplicial_solves) {
    // Same ordering as the simplicial analysis (no second AMD search); the supernodal factor
    // holds the relaxed supernodes' explicit zeros too, which its conversion keeps.
    const cholmod_factor* L = f.llt.factor();
    const auto* perm = static_cast<const int*>(L->Perm);
    f.order.assign(perm, perm + L->n);
    f.convert = true;
    if (!f.analyze_supernodal()) return;  // not usable
    f.entries = std::max(f.entries, static_cast<std::size_t>(f.llt.cholmod().lnz));
  } else if (supernodal_min_flops > 0 && f.flops > supernodal_min_flops) {
    f.llt.setMode(Eigen::CholmodSupernodalLLt);
    cholmod_common& cs = f.llt.cholmod();
    cs.nmethods = 1;
    cs.method[0].ordering = CHOLMOD_AMD;
    cs.postorder = 1;
    f.llt.analyzePattern(f.A);
    // Not usable where the supernodal analysis fails (a factor above CHOLMOD's 2^31 entries).
    if (cholmod_analysis_failed(f.llt)) return;
    f.entries = static_cast<std::size_t>(f.llt.cholmod().lnz);
    f.supernodal = true;
  }
  f.usable = max_factor_entries == 0 || f.entries <= max_factor_entries;
  if (!f.usable) release_factor_inputs();
}

TangentPreconditioner::~TangentPreconditioner() = default;

bool TangentPreconditioner::usable() const {
  return factor_->usable;
}

bool TangentPreconditioner::factored() const {
  return factor_->usable && factor_->factored;
}

int TangentPreconditioner::factorizations() const {
  return factor_->factorizations;
}

std::size_t TangentPreconditioner::factor_entries() const {
  return factor_->entries;
}

double TangentPreconditioner::factor_flops() const {
  return factor_->flops;
}

bool TangentPreconditioner::supernodal() const {
  return factor_->supernodal;
}

bool TangentPreconditioner::supernodal_factorization() const {
  return factor_->convert;
}

int TangentPreconditioner::coordinates_per_pose() const {
  return factor_->p;
}

void TangentPreconditioner::set_split_dots(bool split) {
  factor_->chain.set_split_dots(split);
}

bool TangentPreconditioner::factorize(const Eigen::MatrixXd& X) {
  return factorize_impl(X, nullptr);
}

bool TangentPreconditioner::factorize(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad) {
  if (egrad.rows() != X.rows() || egrad.cols() != X.cols())
    throw std::invalid_argument("TangentPreconditioner::factorize: egrad is not the size of X");
  return factorize_impl(X, &egrad);
}

bool TangentPreconditioner::with_multipliers() const {
  return factor_->with_multipliers;
}

bool TangentPreconditioner::factorize_impl(const Eigen::MatrixXd& X, const Eigen::MatrixXd* egrad) {
  Factor& f = *factor_;
  const int d = f.d, w = d + 1, p = f.p;
  if (!f.usable || f.extra > 0 || X.rows() != d || X.cols() != w * f.m) return false;
  Eigen::MatrixXd Qm(w, w);
  const auto pairs = skew_pairs(d);
  std::vector<Eigen::MatrixXd> G(static_cast<std::size_t>(f.m));
  for (Eigen::Index i = 0; i < f.m; ++i)
    G[static_cast<std::size_t>(i)] = pose_basis(X.block(0, i * w, d, d), pairs);
  // Block (i, j) of A = 2 G_i^T (Q_ij kron I_d) G_j, for i >= j only: CHOLMOD reads A's lower
  // half, so the blocks above the diagonal are not stored.
  double max_diagonal = 0.0;
  for (Eigen::Index j = 0; j < f.m; ++j) {
    const Eigen::MatrixXd& Gj = G[static_cast<std::size_t>(j)];
    const Eigen::Index column_size = (f.block_start[static_cast<std::size_t>(j) + 1] -
                                      f.diagonal_slot[static_cast<std::size_t>(j)]) *
                                     p;
    for (Eigen::Index s = f.diagonal_slot[static_cast<std::size_t>(j)];
         s < f.block_start[static_cast<std::size_t>(j) + 1]; ++s) {
      const Eigen::Index i = f.block_row[static_cast<std::size_t>(s)];
      const double* Qij = f.q_blocks.data() + s * w * w;
      if (egrad && i == j) {
        // S = Q - Lambda: the multipliers sit on the rotation part of the diagonal blocks.
        Qm = Eigen::Map<const Eigen::MatrixXd>(Qij, w, w);
        const Eigen::MatrixXd YG =
            X.block(0, j * w, d, d).transpose() * egrad->block(0, j * w, d, d);
        Qm.topLeftCorner(d, d) -= 0.25 * (YG + YG.transpose());
        Qij = Qm.data();
      }
      double* out = f.A.valuePtr() + f.value_offset(j, s, 0);
      double diagonal = 0.0;
      if (d == 2)
        tangent_block_fixed<2>(Qij, G[static_cast<std::size_t>(i)], Gj, out, column_size,
                               i == j ? &diagonal : nullptr);
      else
        tangent_block_fixed<3>(Qij, G[static_cast<std::size_t>(i)], Gj, out, column_size,
                               i == j ? &diagonal : nullptr);
      max_diagonal = std::max(max_diagonal, diagonal);
    }
  }
  const double lambda = f.relative_shift * std::max(1e-12, max_diagonal);
  f.lambda = lambda;
  for (Eigen::Index j = 0; j < f.m; ++j)
    for (int c = 0; c < p; ++c)
      f.A.valuePtr()[f.value_offset(j, f.diagonal_slot[static_cast<std::size_t>(j)], c) + c] +=
          lambda;
  if (f.convert) {
    // A converted factor is simplicial: the supernodal analysis again (its cost is a small part
    // of the factorization it enables).
    if (!f.llt.factor()->is_super && !f.analyze_supernodal()) {
      f.usable = false;
      f.factored = false;
      return false;
    }
    {
      const SerialBlasLock lock(serial_blas_mutex());  // CHOLMOD's supernodal kernels call BLAS
      f.llt.factorize(f.A);
    }
    if (f.llt.info() == Eigen::Success &&
        !cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/0, /*to_super=*/0, /*to_packed=*/1,
                               /*to_monotonic=*/1, f.llt.factor(), &f.llt.cholmod()))
      throw_cholmod_failure("TangentPreconditioner", "factor conversion", f.llt.cholmod().status,
                            f.A.rows(), f.A.cols());
  } else {
    f.llt.factorize(f.A);
  }
  ++f.factorizations;
  f.calls_since_factor = 0;
  bool positive = f.llt.info() == Eigen::Success;
  if (positive && !f.supernodal) {
    // Simplicial LDL^T does not fail on an indefinite A: check D.
    const cholmod_factor* L = f.llt.factor();
    const auto* col = static_cast<const int*>(L->p);
    const auto* x = static_cast<const double*>(L->x);
    for (std::size_t j = 0; j < L->n && positive; ++j) positive = x[col[j]] > 0;
  }
  f.with_multipliers = egrad != nullptr && positive;
  if (egrad && !positive) return factorize_impl(X, nullptr);
  f.chain.clear();
  if (f.llt.info() != Eigen::Success) {
    f.usable = false;  // keep the caller on its Euclidean preconditioner from now on
    f.factored = false;
    return false;
  }
  f.factored = true;
  f.chain.build(f.llt.factor());  // not built (CHOLMOD solves) for a supernodal factor
  return true;
}

bool TangentPreconditioner::prepare(const Eigen::MatrixXd& X, int refresh_interval) {
  Factor& f = *factor_;
  if (!f.usable || X.rows() != f.d) return false;
  if (!f.factored || (refresh_interval > 0 && f.calls_since_factor >= refresh_interval)) {
    if (!factorize(X)) return false;
  }
  ++f.calls_since_factor;
  return true;
}

Eigen::MatrixXd TangentPreconditioner::apply(const LiftedManifold&, const Eigen::MatrixXd& X,
                                             const Eigen::MatrixXd& V) const {
  Factor& f = *factor_;
  const int d = f.d, w = d + 1, p = f.p;
  const Eigen::Index all = f.m + f.extra;
  if (!factored() || X.rows() != d || V.rows() != d || X.cols() != w * all || V.cols() != X.cols())
    throw std::logic_error("TangentPreconditioner::apply: not factored, or not a rank-d point");
  // b = J^T V, pose by pose: omega_ab = <Y E_ab, V_R> = (Y^T V_R)(b, a) - (Y^T V_R)(a, b),
  // u = Y^T v. The factored poses' coordinates go to the factor's solve, the grown ones' to
  // their diagonal blocks.
  const Eigen::Index skip = w * d * f.m;
  f.b.resize(f.m * p);
  f.extra_b.resize(f.extra * p);
  if (d == 2) {
    tangent_coordinates<2>(X.data(), V.data(), f.m, f.b.data());
    tangent_coordinates<2>(X.data() + skip, V.data() + skip, f.extra, f.extra_b.data());
  } else {
    tangent_coordinates<3>(X.data(), V.data(), f.m, f.b.data());
    tangent_coordinates<3>(X.data() + skip, V.data() + skip, f.extra, f.extra_b.data());
  }
  const double* c = nullptr;
  if (f.extra > 0) {
    f.solve_appended();
    c = f.b.data();
  } else {
    c = f.solve();
  }
  // Z = J c: rotation Y Omega(omega), translation Y u.
  Eigen::MatrixXd Z(d, V.cols());
  if (d == 2) {
    tangent_vector<2>(X.data(), c, f.m, Z.data());
    tangent_vector<2>(X.data() + skip, f.extra_b.data(), f.extra, Z.data() + skip);
  } else {
    tangent_vector<3>(X.data(), c, f.m, Z.data());
    tangent_vector<3>(X.data() + skip, f.extra_b.data(), f.extra, Z.data() + skip);
  }
  return Z;
}

Eigen::MatrixXd TangentPreconditioner::basis(const Eigen::MatrixXd& X) const {
  const Factor& f = *factor_;
  const int d = f.d, w = d + 1, p = f.p;
  if (X.rows() != d || X.cols() != w * f.m)
    throw std::invalid_argument("TangentPreconditioner::basis: not a rank-d point of the block");
  const auto pairs = skew_pairs(d);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(X.size(), f.m * p);
  for (Eigen::Index i = 0; i < f.m; ++i)
    J.block(i * d * w, i * p, d * w, p) = pose_basis(X.block(0, i * w, d, d), pairs);
  return J;
}

}  // namespace tessera
