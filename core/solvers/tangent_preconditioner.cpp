#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <map>
#include <stdexcept>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <vector>

#include "solvers/pose_level_analysis.hpp"

namespace tessera {

namespace {

// Eigen's CHOLMOD wrapper with access to the factor, so that solves can go through
// cholmod_solve2 with workspace kept across calls (Eigen's solve allocates and frees the result
// and two work arrays on every call: three heap blocks per tCG iteration, first-touched each time).
class CholmodLdlt : public Eigen::CholmodDecomposition<SparseMatrix> {
 public:
  cholmod_factor* factor() const { return m_cholmodFactor; }
  // analyzePattern with a fill-reducing ordering given by the caller (`perm`: CHOLMOD's Perm,
  // row perm[k] of A is row k of the permuted matrix) instead of CHOLMOD's own search.
  void analyze_with_ordering(const SparseMatrix& A, std::vector<int>& perm) {
    if (m_cholmodFactor) cholmod_free_factor(&m_cholmodFactor, &cholmod());
    cholmod_sparse a = Eigen::viewAsCholmod(A.selfadjointView<Eigen::Lower>());
    cholmod().nmethods = 1;
    cholmod().method[0].ordering = CHOLMOD_GIVEN;
    m_cholmodFactor = cholmod_analyze_p(&a, perm.data(), nullptr, 0, &cholmod());
    m_isInitialized = true;
    m_info = m_cholmodFactor ? Eigen::Success : Eigen::NumericalIssue;
    m_analysisIsOk = m_cholmodFactor != nullptr;
    m_factorizationIsOk = false;
  }
};

}  // namespace

struct TangentPreconditioner::Factor {
  ~Factor() {
    cholmod_common& c = llt.cholmod();
    for (cholmod_dense** x : {&solve_x, &solve_y, &solve_e})
      if (*x) cholmod_free_dense(x, &c);
  }
  // A^{-1} b for the right-hand side in `b`; the result lives in solve_x (valid until the next
  // call). The same numeric solve as CholmodDecomposition::solve (cholmod_solve calls
  // cholmod_solve2 with fresh workspace), hence the same result.
  const double* solve() {
    cholmod_dense rhs;
    rhs.nrow = static_cast<std::size_t>(b.size());
    rhs.ncol = 1;
    rhs.nzmax = rhs.nrow;
    rhs.d = rhs.nrow;
    rhs.x = b.data();
    rhs.z = nullptr;
    rhs.xtype = CHOLMOD_REAL;
    rhs.dtype = CHOLMOD_DOUBLE;
    cholmod_common& c = llt.cholmod();
    if (!cholmod_solve2(CHOLMOD_A, llt.factor(), &rhs, nullptr, &solve_x, nullptr, &solve_y,
                        &solve_e, &c))
      throw std::runtime_error("TangentPreconditioner: CHOLMOD solve failed");
    return static_cast<const double*>(solve_x->x);
  }

  int d = 0;
  int p = 0;  // coordinates per pose
  Eigen::Index m = 0;
  double relative_shift = 0.0;
  // Pose-block pattern of Q_BB by block columns: the row blocks of block column j are
  // block_row[block_start[j] .. block_start[j+1]), increasing, the diagonal always included.
  std::vector<Eigen::Index> block_start, block_row, diagonal_slot;
  // Q_BB's (d+1) x (d+1) block of each pose-block pair, column-major, in block_row order.
  std::vector<double> q_blocks;
  // A with its full pattern (every pose-block pair p x p dense; CHOLMOD reads the lower half).
  SparseMatrix A;
  CholmodLdlt llt;
  // Solve workspace, reused by every apply (agents apply their own preconditioner only).
  Eigen::VectorXd b;
  cholmod_dense *solve_x = nullptr, *solve_y = nullptr, *solve_e = nullptr;
  std::size_t entries = 0;
  double flops = 0.0;
  bool supernodal = false;
  bool with_multipliers = false;
  bool usable = false;
  bool factored = false;
  double lambda = 0.0;  // the shift of the last factorization
  // grow(): the poses after the factored m, appended to the factor (see grow()). T: the old
  // poses that new measurements touch (t = |T| p coordinates). W = L^-1 P U (U: T's coordinates;
  // rows in the factor's order), K = U^T A_oo^-1 U, H = (Delta^-1 + K)^-1 with Delta the new
  // measurements' share of A on T, B = A_on's rows of T, S the grown poses' Schur complement.
  Eigen::Index extra = 0;
  std::unique_ptr<Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>> extra_factor;  // of S
  SparseMatrix extra_w, extra_bt;
  Eigen::MatrixXd extra_k, extra_h;
  Eigen::VectorXd extra_b, y;  // the grown poses' coordinates; the old ones' in factor order

  // The held factor's solve with the grown poses appended (grow()): b's old coordinates, extra_b
  // the grown ones'; both replaced by the solution (b in the original order).
  void solve_appended() {
    const cholmod_factor* L = llt.factor();
    const auto* Lp = static_cast<const int*>(L->p);
    const auto* Li = static_cast<const int*>(L->i);
    const auto* Lnz = static_cast<const int*>(L->nz);
    const auto* Lx = static_cast<const double*>(L->x);
    const auto* perm = static_cast<const int*>(L->Perm);
    const Eigen::Index n = b.size();
    y.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) y(k) = b(perm[k]);
    for (Eigen::Index k = 0; k < n; ++k) {  // y = L^-1 P b
      const double yk = y(k);
      if (yk != 0.0)
        for (int q = Lp[k] + 1; q < Lp[k] + Lnz[k]; ++q) y(Li[q]) -= Lx[q] * yk;
    }
    // U^T A'^-1 b_o = a - K H a with a = W^T D^-1 y (A' = A_oo + U Delta U^T, Woodbury).
    auto d_inv = [&](const Eigen::VectorXd& v) {
      Eigen::VectorXd u(n);
      for (Eigen::Index k = 0; k < n; ++k) u(k) = v(k) / Lx[Lp[k]];
      return u;
    };
    const Eigen::VectorXd a = extra_w.transpose() * d_inv(y);
    const Eigen::VectorXd ut = a - extra_k * (extra_h * a);
    extra_b -= extra_bt.transpose() * ut;  // z_n = S^-1 (b_n - A_no A'^-1 b_o)
    extra_b = extra_factor->solve(extra_b);
    // z_o = A'^-1 (b_o - A_on z_n), in L's frame: v = y - W B z_n, then v - W H W^T D^-1 v,
    // where W^T D^-1 v = a - K B z_n: one product with W.
    const Eigen::VectorXd bz = extra_bt * extra_b;
    const Eigen::VectorXd a2 = a - extra_k * bz;
    y -= extra_w * (bz + extra_h * a2);
    for (Eigen::Index k = n; k-- > 0;) {
      double s = y(k) / Lx[Lp[k]];
      for (int q = Lp[k] + 1; q < Lp[k] + Lnz[k]; ++q) s -= Lx[q] * y(Li[q]);
      y(k) = s;
    }
    for (Eigen::Index k = 0; k < n; ++k) b(perm[k]) = y(k);
  }
  int factorizations = 0;
  int calls_since_factor = 0;

  // Offset in A's value array of entry (0, c) of the block in slot s of block column j.
  Eigen::Index value_offset(Eigen::Index j, Eigen::Index s, int c) const {
    return A.outerIndexPtr()[j * p + c] + (s - block_start[static_cast<std::size_t>(j)]) * p;
  }
};

namespace {

// The rotation-coordinate index pairs (a < b) of the skew basis E_ab = e_b e_a^T - e_a e_b^T.
std::vector<std::pair<int, int>> skew_pairs(int d) {
  std::vector<std::pair<int, int>> out;
  for (int a = 0; a < d; ++a)
    for (int b = a + 1; b < d; ++b) out.emplace_back(a, b);
  return out;
}

// G (d(d+1) x p): the pose's tangent basis vectors, each the column-major vec of a d x (d+1)
// pose block, at rotation Y (d x d).
Eigen::MatrixXd pose_basis(const Eigen::Ref<const Eigen::MatrixXd>& Y,
                           const std::vector<std::pair<int, int>>& pairs) {
  const Eigen::Index d = Y.rows();
  const Eigen::Index nr = static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(d * (d + 1), nr + d);
  for (Eigen::Index k = 0; k < nr; ++k) {
    const auto [a, b] = pairs[static_cast<std::size_t>(k)];
    // Y E_ab: column a is Y e_b, column b is -Y e_a.
    G.block(a * d, k, d, 1) = Y.col(b);
    G.block(b * d, k, d, 1) = -Y.col(a);
  }
  G.block(d * d, nr, d, d) = Y;
  return G;
}

// Block (i, j) of A, 2 G_i^T (Q_ij kron I_d) G_j (p x p), into B; T (d(d+1) x p) is scratch.
void tangent_block(const Eigen::Ref<const Eigen::MatrixXd>& Qij, const Eigen::MatrixXd& Gi,
                   const Eigen::MatrixXd& Gj, int d, Eigen::MatrixXd& T, Eigen::MatrixXd& B) {
  const int w = d + 1;
  for (int t = 0; t < w; ++t) {
    auto row = T.middleRows(t * d, d);
    row.setZero();
    for (int u = 0; u < w; ++u)
      if (Qij(t, u) != 0.0) row.noalias() += Qij(t, u) * Gj.middleRows(u * d, d);
  }
  B.noalias() = 2.0 * Gi.transpose() * T;
}

// tangent_block for a fixed d (2 or 3), written straight into A's value array (column c of the
// block at out + c * stride): fixed-size products instead of dynamic ones, whose per-call
// dispatch and temporaries made the assembly as costly as the numeric factorization (a block
// that grew is assembled again at every online step). `diagonal` (a diagonal block, i = j):
// the block is made exactly symmetric and its largest diagonal entry returned there.
template <int D>
void tangent_block_fixed(const double* Qij, const Eigen::MatrixXd& Gi, const Eigen::MatrixXd& Gj,
                         double* out, Eigen::Index stride, double* diagonal = nullptr) {
  constexpr int W = D + 1, P = D * (D + 1) / 2;
  const Eigen::Map<const Eigen::Matrix<double, D * W, P>> gi(Gi.data()), gj(Gj.data());
  Eigen::Matrix<double, D * W, P> T;
  for (int t = 0; t < W; ++t) {
    auto row = T.template middleRows<D>(t * D);
    row.setZero();
    for (int u = 0; u < W; ++u) {
      const double q = Qij[u * W + t];
      if (q != 0.0) row.noalias() += q * gj.template middleRows<D>(u * D);
    }
  }
  Eigen::Matrix<double, P, P> B = 2.0 * gi.transpose() * T;
  if (diagonal) {
    B = (0.5 * (B + B.transpose())).eval();  // exactly symmetric
    *diagonal = B.diagonal().maxCoeff();
  }
  for (int c = 0; c < P; ++c) std::copy(B.col(c).data(), B.col(c).data() + P, out + c * stride);
}

// The pose-level estimate is skipped to the exact analysis below this multiple of the cap,
// so that a factor near the cap is decided by its exact size as before.
constexpr double kSkipFactor = 2.0;

// Entries of A's LDL^T factor estimated from the pose-level pattern (`rows`: the row blocks of
// each block column, diagonal included): the pose-level factor's entries (same AMD ordering,
// symbolic only), each off-diagonal block p x p dense and each diagonal block triangular.
// `order` (when not null) receives the pose-level analysis' ordering (CHOLMOD's Perm, postordered).
double pose_level_fill_estimate(const std::vector<std::vector<Eigen::Index>>& rows, int p,
                                std::vector<int>* order = nullptr) {
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
  const double md = static_cast<double>(m), block_entries = a.factor_entries;
  return (block_entries - md) * p * p + md * p * (p + 1) / 2.0;
}

}  // namespace

TangentPreconditioner::TangentPreconditioner(const BlockProblem& problem, double relative_shift,
                                             std::size_t max_factor_entries,
                                             double supernodal_min_flops)
    : factor_(std::make_unique<Factor>()) {
  if (!(relative_shift >= 0))
    throw std::invalid_argument("TangentPreconditioner: relative_shift must be >= 0");
  Factor& f = *factor_;
  f.d = problem.dim();
  f.p = f.d * (f.d + 1) / 2;
  f.m = static_cast<Eigen::Index>(problem.num_owned());
  f.relative_shift = relative_shift;
  const int w = f.d + 1;
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
  {
    const double estimate = pose_level_fill_estimate(rows, f.p, &pose_order);
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
  // A's pattern: block column j's columns each hold p rows per row block.
  const Eigen::Index n = f.m * f.p;
  const Eigen::Index nnz = static_cast<Eigen::Index>(f.block_row.size()) * f.p * f.p;
  f.A.resize(n, n);
  f.A.resizeNonZeros(nnz);
  Eigen::Index pos = 0;
  for (Eigen::Index j = 0; j < f.m; ++j)
    for (int c = 0; c < f.p; ++c) {
      f.A.outerIndexPtr()[j * f.p + c] = static_cast<int>(pos);
      for (Eigen::Index s = f.block_start[static_cast<std::size_t>(j)];
           s < f.block_start[static_cast<std::size_t>(j) + 1]; ++s)
        for (int r = 0; r < f.p; ++r) {
          f.A.innerIndexPtr()[pos] =
              static_cast<int>(f.block_row[static_cast<std::size_t>(s)] * f.p + r);
          f.A.valuePtr()[pos] = 0.0;
          ++pos;
        }
    }
  f.A.outerIndexPtr()[n] = static_cast<int>(pos);

  // Symbolic analysis once (the pose-level AMD ordering above, else AMD; simplicial LDL^T:
  // supernodal LL^T took 6 % more instructions on the online steps of a 1,000-pose grid).
  f.llt.setMode(Eigen::CholmodLDLt);
  cholmod_common& c = f.llt.cholmod();
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_AMD;
  c.postorder = 1;
  if (f.m > 0 && pose_order.size() == static_cast<std::size_t>(f.m)) {
    std::vector<int> order(static_cast<std::size_t>(n));
    for (Eigen::Index k = 0; k < f.m; ++k)
      for (int q = 0; q < f.p; ++q)
        order[static_cast<std::size_t>(k * f.p + q)] =
            pose_order[static_cast<std::size_t>(k)] * f.p + q;
    f.llt.analyze_with_ordering(f.A, order);
  } else {
    f.llt.analyzePattern(f.A);
  }
  if (f.llt.info() != Eigen::Success) return;  // not usable
  f.entries = static_cast<std::size_t>(f.llt.cholmod().lnz);
  f.flops = f.llt.cholmod().fl;
  // A dense factorization (3D graphs: p = 6 coordinates a pose, (6/4)^3 the flops of the
  // Euclidean factor of Q) is several times cheaper with BLAS on its supernodes. The re-analysis
  // repeats the AMD ordering, a small part of such a factorization.
  if (supernodal_min_flops > 0 && f.flops > supernodal_min_flops) {
    f.llt.setMode(Eigen::CholmodSupernodalLLt);
    cholmod_common& cs = f.llt.cholmod();
    cs.nmethods = 1;
    cs.method[0].ordering = CHOLMOD_AMD;
    cs.postorder = 1;
    f.llt.analyzePattern(f.A);
    if (f.llt.info() != Eigen::Success) return;  // not usable
    f.entries = static_cast<std::size_t>(f.llt.cholmod().lnz);
    f.supernodal = true;
  }
  f.usable = max_factor_entries == 0 || f.entries <= max_factor_entries;
  if (!f.usable) {  // what only the factor needs goes now, not with the preconditioner
    f.A = SparseMatrix();
    std::vector<double>().swap(f.q_blocks);
    std::vector<Eigen::Index>().swap(f.block_row);
    std::vector<Eigen::Index>().swap(f.block_start);
    std::vector<Eigen::Index>().swap(f.diagonal_slot);
  }
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

int TangentPreconditioner::coordinates_per_pose() const {
  return factor_->p;
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
  // half, so the blocks above the diagonal are never computed (they stay 0).
  double max_diagonal = 0.0;
  for (Eigen::Index j = 0; j < f.m; ++j) {
    const Eigen::MatrixXd& Gj = G[static_cast<std::size_t>(j)];
    const Eigen::Index begin = f.block_start[static_cast<std::size_t>(j)];
    const Eigen::Index column_size = (f.block_start[static_cast<std::size_t>(j) + 1] - begin) * p;
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
  f.llt.factorize(f.A);
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
  if (f.llt.info() != Eigen::Success) {
    f.usable = false;  // keep the caller on its Euclidean preconditioner from now on
    f.factored = false;
    return false;
  }
  f.factored = true;
  return true;
}

bool TangentPreconditioner::grow(const BlockProblem& problem, const Eigen::MatrixXd& X) {
  Factor& f = *factor_;
  const int d = f.d, w = d + 1, p = f.p;
  const Eigen::Index total = static_cast<Eigen::Index>(problem.num_owned());
  if (!factored() || f.supernodal || problem.dim() != d || total < f.m + f.extra || X.rows() != d ||
      X.cols() != w * total)
    return false;
  const cholmod_factor* L = f.llt.factor();
  if (L == nullptr || L->is_super || L->is_ll || L->xtype != CHOLMOD_REAL) return false;
  // The grown poses (this growth's and earlier ones', again at X with every measurement so far)
  // are appended to the held factor of the old poses' A_oo as one block LDL^T:
  //   [A_oo A_on; A_no A_nn] = [L 0; W^T D^-1 I] [D 0; 0 S] [L^T D^-1 W; 0 I]  (A_oo = L D L^T,
  // permuted), W = L^-1 A_on, S = A_nn - W^T D^-1 W. A_oo stays the factored one (stale: from
  // an earlier point and without the new measurements' share on old poses), the rest is exact.
  // Why not the grown poses on their own (block Jacobi): a new chain is bent by its closures to
  // old poses, and without A_on a 1,000-pose grid took 2.3x the CG iterations at 10 % growth.
  // W is sparse: a column reaches only the elimination tree's path above the few old poses a
  // new measurement touches.
  const Eigen::Index first = f.m, extra = total - f.m;
  const Eigen::Index n_old = f.m * p, n_new = extra * p;
  const SparseMatrix& Q = problem.data_matrix();
  const auto pairs = skew_pairs(d);
  std::vector<Eigen::MatrixXd> G(static_cast<std::size_t>(total));
  auto basis_of = [&](Eigen::Index i) -> const Eigen::MatrixXd& {
    Eigen::MatrixXd& g = G[static_cast<std::size_t>(i)];
    if (g.size() == 0) g = pose_basis(X.block(0, i * w, d, d), pairs);
    return g;
  };
  // Q's pose blocks in the grown poses' block columns: (row pose i, column pose j), i >= j
  // among the grown poses, any old i.
  std::map<std::pair<Eigen::Index, Eigen::Index>, Eigen::MatrixXd> qb;
  for (Eigen::Index j = first; j < total; ++j)
    for (int s = 0; s < w; ++s)
      for (SparseMatrix::InnerIterator it(Q, j * w + s); it; ++it) {
        const Eigen::Index i = it.row() / w;
        if (i >= first && i < j) continue;  // upper half of A_nn
        Eigen::MatrixXd& blk = qb[{i, j}];
        if (blk.size() == 0) blk = Eigen::MatrixXd::Zero(w, w);
        blk(it.row() % w, s) = it.value();
      }
  // T: old poses coupled to a grown one, or whose own block of Q got new measurements (new
  // closures and cut edges at old poses: their share Delta of A_oo, which the held factor lacks
  // and without which [A_oo A_on; A_no A_nn] is indefinite on a 1,000-pose grid).
  std::map<Eigen::Index, int> t_index;
  for (const auto& [ij, Qij] : qb)
    if (ij.first < first) t_index.emplace(ij.first, 0);
  std::map<Eigen::Index, Eigen::MatrixXd> dq;  // Q_ii now minus Q_ii when factored
  for (Eigen::Index i = 0; i < first; ++i) {
    Eigen::MatrixXd now = Eigen::MatrixXd::Zero(w, w);
    for (int s = 0; s < w; ++s)
      for (SparseMatrix::InnerIterator it(Q, i * w + s); it; ++it)
        if (it.row() / w == i) now(it.row() % w, s) = it.value();
    const double* was = f.q_blocks.data() + f.diagonal_slot[static_cast<std::size_t>(i)] * w * w;
    now -= Eigen::Map<const Eigen::MatrixXd>(was, w, w);
    if (now.cwiseAbs().maxCoeff() > 0.0) {
      dq.emplace(i, now);
      t_index.emplace(i, 0);
    }
  }
  int tn = 0;
  for (auto& [i, k] : t_index) k = tn++;
  const Eigen::Index t = static_cast<Eigen::Index>(tn) * p;
  std::vector<Eigen::Triplet<double>> t_nn, t_b;
  Eigen::MatrixXd T(d * w, p), B(p, p);
  for (const auto& [ij, Qij] : qb) {
    const auto [i, j] = ij;
    tangent_block(Qij, basis_of(i), basis_of(j), d, T, B);
    const Eigen::Index cj = (j - first) * p;
    if (i < first) {
      const Eigen::Index ri = static_cast<Eigen::Index>(t_index.at(i)) * p;
      for (int c = 0; c < p; ++c)
        for (int r = 0; r < p; ++r) t_b.emplace_back(ri + r, cj + c, B(r, c));
      continue;
    }
    const Eigen::Index ci = (i - first) * p;
    if (i == j) {
      B = (0.5 * (B + B.transpose())).eval();
      B.diagonal().array() += f.lambda;
    }
    for (int c = 0; c < p; ++c)
      for (int r = 0; r < p; ++r) {
        t_nn.emplace_back(ci + r, cj + c, B(r, c));
        if (i != j) t_nn.emplace_back(cj + c, ci + r, B(r, c));
      }
  }
  Eigen::MatrixXd delta = Eigen::MatrixXd::Zero(t, t);
  for (const auto& [i, q] : dq) {
    tangent_block(q, basis_of(i), basis_of(i), d, T, B);
    const Eigen::Index ri = static_cast<Eigen::Index>(t_index.at(i)) * p;
    delta.block(ri, ri, p, p) = 0.5 * (B + B.transpose());
  }
  SparseMatrix Bt(t, n_new);
  Bt.setFromTriplets(t_b.begin(), t_b.end());
  // W = L^-1 P U, column by column: a sparse forward solve over the reach of one coordinate
  // (its elimination-tree ancestors, in increasing order).
  const auto* Lp = static_cast<const int*>(L->p);
  const auto* Li = static_cast<const int*>(L->i);
  const auto* Lnz = static_cast<const int*>(L->nz);
  const auto* Lx = static_cast<const double*>(L->x);
  const auto* perm = static_cast<const int*>(L->Perm);
  std::vector<int> position(static_cast<std::size_t>(n_old));
  for (Eigen::Index k = 0; k < n_old; ++k)
    position[static_cast<std::size_t>(perm[k])] = static_cast<int>(k);
  std::vector<int> parent(static_cast<std::size_t>(n_old), -1);
  for (Eigen::Index k = 0; k < n_old; ++k)
    for (int q = Lp[k] + 1; q < Lp[k] + Lnz[k]; ++q)
      if (parent[static_cast<std::size_t>(k)] < 0 || Li[q] < parent[static_cast<std::size_t>(k)])
        parent[static_cast<std::size_t>(k)] = Li[q];
  std::vector<double> x(static_cast<std::size_t>(n_old), 0.0);
  std::vector<char> mark(static_cast<std::size_t>(n_old), 0);
  std::vector<int> reach;
  std::vector<Eigen::Triplet<double>> t_w;
  for (const auto& [i, ti] : t_index)
    for (int r = 0; r < p; ++r) {
      const Eigen::Index col = static_cast<Eigen::Index>(ti) * p + r;
      reach.clear();
      int k = position[static_cast<std::size_t>(i * p + r)];
      x[static_cast<std::size_t>(k)] = 1.0;
      while (k >= 0 && !mark[static_cast<std::size_t>(k)]) {
        mark[static_cast<std::size_t>(k)] = 1;
        reach.push_back(k);
        k = parent[static_cast<std::size_t>(k)];
      }
      std::sort(reach.begin(), reach.end());
      for (int kk : reach) {
        const double xk = x[static_cast<std::size_t>(kk)];
        if (xk != 0.0)
          for (int q = Lp[kk] + 1; q < Lp[kk] + Lnz[kk]; ++q)
            x[static_cast<std::size_t>(Li[q])] -= Lx[q] * xk;
      }
      for (int kk : reach) {
        const double xk = x[static_cast<std::size_t>(kk)];
        if (xk != 0.0) t_w.emplace_back(kk, col, xk);
        x[static_cast<std::size_t>(kk)] = 0.0;
        mark[static_cast<std::size_t>(kk)] = 0;
      }
    }
  SparseMatrix Wu(n_old, t);
  Wu.setFromTriplets(t_w.begin(), t_w.end());
  Eigen::VectorXd d_inv(n_old);
  for (Eigen::Index k = 0; k < n_old; ++k) d_inv(k) = 1.0 / Lx[Lp[k]];
  const SparseMatrix Wd = d_inv.asDiagonal() * Wu;
  Eigen::MatrixXd K = Eigen::MatrixXd(SparseMatrix(Wu.transpose() * Wd));
  K = (0.5 * (K + K.transpose())).eval();
  // H = (Delta^-1 + K)^-1 = Delta (I + K Delta)^-1 (Delta may be singular).
  const Eigen::MatrixXd I_kd = Eigen::MatrixXd::Identity(t, t) + K * delta;
  Eigen::MatrixXd H = I_kd.transpose().partialPivLu().solve(delta).transpose();
  H = (0.5 * (H + H.transpose())).eval();
  // S = A_nn - B^T (K - K H K) B over the grown coordinates B touches.
  const Eigen::MatrixXd E = K - K * H * K;
  std::vector<Eigen::Index> cols;
  for (Eigen::Index c = 0; c < n_new; ++c)
    if (Bt.col(c).nonZeros() > 0) cols.push_back(c);
  Eigen::MatrixXd Bc = Eigen::MatrixXd::Zero(t, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t k = 0; k < cols.size(); ++k)
    for (SparseMatrix::InnerIterator it(Bt, cols[k]); it; ++it)
      Bc(it.row(), static_cast<Eigen::Index>(k)) = it.value();
  const Eigen::MatrixXd Sc = Bc.transpose() * E * Bc;
  for (std::size_t a = 0; a < cols.size(); ++a)
    for (std::size_t b = 0; b < cols.size(); ++b)
      t_nn.emplace_back(cols[a], cols[b],
                        -Sc(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)));
  SparseMatrix S(n_new, n_new);
  S.setFromTriplets(t_nn.begin(), t_nn.end());
  auto ldlt = std::make_unique<Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>>(S);
  // The held A_oo is from an earlier point: where it no longer fits A_on (rotations moved
  // along a weakly held direction), S is not positive definite and the block is refactored.
  if (ldlt->info() != Eigen::Success || !(ldlt->vectorD().array() > 0).all()) return false;
  f.extra_factor = std::move(ldlt);
  f.extra_w = std::move(Wu);
  f.extra_bt = std::move(Bt);
  f.extra_k = std::move(K);
  f.extra_h = std::move(H);
  f.extra = extra;
  return true;
}

Eigen::Index TangentPreconditioner::grown_poses() const {
  return factor_->extra;
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

namespace {

// J^T V and J c pose by pose for a fixed d (2 or 3): fixed-size arrays instead of dynamic d x d
// products (whose per-coefficient dispatch was ~40% of an apply on parking-garage). Every dot
// product is summed over k = 0..d-1 in order, as Eigen's lazy products of the previous
// version did, so the result is bit-identical to it.
template <int D>
void tangent_coordinates(const double* X, const double* V, Eigen::Index m, double* b) {
  constexpr int W = D + 1, P = D * (D + 1) / 2, NR = P - D;
  for (Eigen::Index i = 0; i < m; ++i) {
    const double* Y = X + i * W * D;   // d x d rotation block, column-major
    const double* Vi = V + i * W * D;  // d x (d+1) pose block
    double Wm[D][W];                   // Wm[a][c] = (Y^T V_i)(a, c)
    for (int c = 0; c < W; ++c)
      for (int a = 0; a < D; ++a) {
        double s = Y[a * D] * Vi[c * D];
        for (int k = 1; k < D; ++k) s += Y[a * D + k] * Vi[c * D + k];
        Wm[a][c] = s;
      }
    double* bi = b + i * P;
    int k = 0;
    for (int a = 0; a < D; ++a)
      for (int bb = a + 1; bb < D; ++bb, ++k) bi[k] = Wm[bb][a] - Wm[a][bb];
    for (int a = 0; a < D; ++a) bi[NR + a] = Wm[a][D];
  }
}

template <int D>
void tangent_vector(const double* X, const double* c, Eigen::Index m, double* Z) {
  constexpr int W = D + 1, P = D * (D + 1) / 2, NR = P - D;
  for (Eigen::Index i = 0; i < m; ++i) {
    const double* Y = X + i * W * D;
    const double* ci = c + i * P;
    double S[W][D] = {};  // S[col][row]: Omega(omega) and u
    int k = 0;
    for (int a = 0; a < D; ++a)
      for (int bb = a + 1; bb < D; ++bb, ++k) {
        S[a][bb] += ci[k];
        S[bb][a] -= ci[k];
      }
    for (int a = 0; a < D; ++a) S[D][a] = ci[NR + a];
    double* Zi = Z + i * W * D;
    for (int col = 0; col < W; ++col)
      for (int row = 0; row < D; ++row) {
        double s = Y[row] * S[col][0];
        for (int kk = 1; kk < D; ++kk) s += Y[kk * D + row] * S[col][kk];
        Zi[col * D + row] = s;
      }
  }
}

}  // namespace

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
