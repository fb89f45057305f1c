#include "certification/interface_schur.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <unordered_map>

#include "solvers/cholmod_checked.hpp"
#include "solvers/interface_last_order.hpp"
#include "util/serial_blas.hpp"

// BLAS (the one CHOLMOD's supernodal factorization runs on): C = A A^T, lower triangle.
extern "C" void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k,
                       const double* alpha, const double* a, const int* lda, const double* beta,
                       double* c, const int* ldc);

namespace tessera {

namespace {

// L L^T of a lower triangular L, both triangles (BLAS syrk: the dense kernels with FMA that
// Eigen's portable build does not use; a third of the instructions of Eigen's rankUpdate).
Eigen::MatrixXd lower_times_transpose(const Eigen::MatrixXd& L) {
  const int n = static_cast<int>(L.rows());
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  if (n == 0) return out;
  const double one = 1.0, zero = 0.0;
  const SerialBlasLock lock(serial_blas_mutex());
  dsyrk_("L", "N", &n, &n, &one, L.data(), &n, &zero, out.data(), &n);
  out.triangularView<Eigen::StrictlyUpper>() = out.transpose();
  return out;
}

// CHOLMOD's supernodal LL^T (dense BLAS kernels on the factor's dense blocks: the interface's
// trailing block of an agent's matrix, most of agent 0's Sigma). Quiet: a matrix that is not
// positive definite is an expected verdict here, not an error to print. LL^T always (the
// simplicial default LDL^T exists for indefinite matrices, so it would pass every test).
class SupernodalCholesky {
 public:
  // `ordering`: CHOLMOD_NATURAL (the caller's order, not postordered) or CHOLMOD_AMD.
  explicit SupernodalCholesky(int ordering) {
    cholmod_start(&c_);
    c_.print = 0;
    c_.supernodal = CHOLMOD_SUPERNODAL;
    c_.final_ll = 1;
    c_.nmethods = 1;
    c_.method[0].ordering = ordering;
    c_.postorder = ordering == CHOLMOD_NATURAL ? 0 : 1;
  }
  ~SupernodalCholesky() {
    if (L_) cholmod_free_factor(&L_, &c_);
    cholmod_finish(&c_);
  }
  SupernodalCholesky(const SupernodalCholesky&) = delete;
  SupernodalCholesky& operator=(const SupernodalCholesky&) = delete;

  // Factors `lower` (the lower triangle of a symmetric matrix). Returns the column where the
  // factorization failed (the leading principal submatrix up to it is not positive definite),
  // or n when the matrix is positive definite.
  Eigen::Index factor(const SparseMatrix& lower) {
    cholmod_sparse a = Eigen::viewAsCholmod(lower.selfadjointView<Eigen::Lower>());
    L_ = cholmod_analyze(&a, &c_);
    if (!L_)
      throw_cholmod_failure("certificate (interface Schur complement)", "analysis", c_.status,
                            lower.rows(), lower.cols());
    {
      const SerialBlasLock lock(serial_blas_mutex());
      cholmod_factorize(&a, L_, &c_);
    }
    if (c_.status < CHOLMOD_OK)
      throw_cholmod_failure("certificate (interface Schur complement)", "factorization", c_.status,
                            lower.rows(), lower.cols());
    return static_cast<Eigen::Index>(L_->minor);
  }

  // The factor's block of rows and columns >= first (a natural ordering's trailing block).
  Eigen::MatrixXd trailing_block(Eigen::Index first) const {
    const auto n = static_cast<Eigen::Index>(L_->n);
    const int* perm = static_cast<const int*>(L_->Perm);
    for (Eigen::Index k = first; k < n; ++k)
      if (perm && perm[k] != k) throw std::logic_error("certificate: the factor was reordered");
    Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n - first, n - first);
    const int* super = static_cast<const int*>(L_->super);
    const int* pi = static_cast<const int*>(L_->pi);
    const int* px = static_cast<const int*>(L_->px);
    const int* rows = static_cast<const int*>(L_->s);
    const double* x = static_cast<const double*>(L_->x);
    for (std::size_t s = 0; s < L_->nsuper; ++s) {
      const int c0 = super[s], c1 = super[s + 1], nr = pi[s + 1] - pi[s];
      for (int j = std::max<int>(c0, static_cast<int>(first)); j < c1; ++j)
        for (int r = j - c0; r < nr; ++r) {
          const int i = rows[pi[s] + r];
          out(i - first, j - first) = x[px[s] + static_cast<std::ptrdiff_t>(j - c0) * nr + r];
        }
    }
    return out;
  }

 private:
  cholmod_common c_;
  cholmod_factor* L_ = nullptr;
};

}  // namespace

InterfaceSchurBlock local_interface_schur(const BlockProblem& problem, const SparseMatrix& lambda,
                                          const Eigen::VectorXd& shift,
                                          const std::vector<std::size_t>& interface_poses) {
  // Every pose with a cut measurement is kept: no pose of another block couples to an
  // eliminated one, so the predicate on the neighbours' poses is never asked about that.
  return local_separator_schur(problem, lambda, shift, interface_poses,
                               [](std::size_t) { return true; });
}

InterfaceSchurBlock local_separator_schur(const BlockProblem& problem, const SparseMatrix& lambda,
                                          const Eigen::VectorXd& shift,
                                          const std::vector<std::size_t>& kept,
                                          const std::function<bool(std::size_t)>& in_separator) {
  InterfaceSchurBlock out;
  const int d = problem.dim();
  const Eigen::Index w = d + 1;
  const auto& owned = problem.owned();
  const auto& neighbors = problem.neighbors();
  const SparseMatrix& Qnb = problem.neighbor_matrix();
  const Eigen::Index n = w * static_cast<Eigen::Index>(owned.size());
  std::unordered_map<std::size_t, Eigen::Index> slot;
  slot.reserve(owned.size());
  for (std::size_t s = 0; s < owned.size(); ++s)
    slot.emplace(owned[s], static_cast<Eigen::Index>(s));

  // New position of each coordinate: the eliminated poses' (fill-reducing order) first, then
  // the kept own poses in `kept` order, then the foreign separator poses coupled to an
  // eliminated pose (ascending ids), so the factor's trailing block is the Schur complement's.
  std::vector<Eigen::Index> pos(static_cast<std::size_t>(n), -1);
  const Eigen::Index nK = w * static_cast<Eigen::Index>(kept.size());
  std::vector<char> is_kept(owned.size(), 0);
  for (std::size_t k = 0; k < kept.size(); ++k) {
    auto it = slot.find(kept[k]);
    if (it == slot.end()) throw std::runtime_error("interface pose not owned by the block");
    is_kept[static_cast<std::size_t>(it->second)] = 1;
  }
  // Foreign separator poses next to an eliminated pose: neighbour slots, ascending global id.
  std::vector<char> foreign_flag(neighbors.size(), 0);
  for (Eigen::Index col = 0; col < n; ++col) {
    if (is_kept[static_cast<std::size_t>(col / w)]) continue;
    for (SparseMatrix::InnerIterator it(Qnb, col); it; ++it)
      if (it.value() != 0.0) foreign_flag[static_cast<std::size_t>(it.row() / w)] = 1;
  }
  std::vector<std::size_t> foreign;  // neighbour slots
  for (std::size_t k = 0; k < neighbors.size(); ++k)
    if (foreign_flag[k]) {
      if (!in_separator(neighbors[k]))
        throw std::runtime_error("certificate: a cut measurement with no separator endpoint");
      foreign.push_back(k);
    }
  std::sort(foreign.begin(), foreign.end(),
            [&](std::size_t a, std::size_t b) { return neighbors[a] < neighbors[b]; });
  const Eigen::Index nF = w * static_cast<Eigen::Index>(foreign.size());
  const Eigen::Index nI = n - nK;
  const Eigen::Index nG = nK + nF;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const Eigen::Index s = slot.at(kept[k]);
    for (Eigen::Index c = 0; c < w; ++c)
      pos[static_cast<std::size_t>(w * s + c)] = nI + w * static_cast<Eigen::Index>(k) + c;
  }
  std::vector<Eigen::Index> foreign_pos(neighbors.size() * static_cast<std::size_t>(w), -1);
  for (std::size_t k = 0; k < foreign.size(); ++k)
    for (Eigen::Index c = 0; c < w; ++c)
      foreign_pos[static_cast<std::size_t>(w * static_cast<Eigen::Index>(foreign[k]) + c)] =
          n + w * static_cast<Eigen::Index>(k) + c;
  out.poses = kept;
  for (std::size_t k : foreign) out.poses.push_back(neighbors[k]);

  const SparseMatrix A = problem.data_matrix() - lambda;
  // The eliminated poses' order is found at the pose level (a pose's w coordinates stay
  // together, in order): the pattern's pose blocks are dense, so AMD on the poses orders what AMD
  // on the coordinates would, on w^2 times fewer entries (it was a quarter of the agents' test).
  std::vector<Eigen::Index> pose_pos(owned.size(), -1);
  for (std::size_t k = 0; k < kept.size(); ++k)
    pose_pos[static_cast<std::size_t>(slot.at(kept[k]))] =
        (n - nK) / w + static_cast<Eigen::Index>(k);
  place_interior_first(pose_pos, [&](const auto& add) {
    for (Eigen::Index col = 0; col < n; col += w)
      if (pose_pos[static_cast<std::size_t>(col / w)] < 0)  // an interior pose
        for (Eigen::Index c = col; c < col + w; ++c)
          for (SparseMatrix::InnerIterator it(A, c); it; ++it) add(it.row() / w, col / w);
  });
  for (std::size_t p = 0; p < owned.size(); ++p)
    if (!is_kept[p])
      for (Eigen::Index c = 0; c < w; ++c)
        pos[static_cast<std::size_t>(w * static_cast<Eigen::Index>(p) + c)] = w * pose_pos[p] + c;

  // The foreign poses' diagonal is a placeholder kappa I (their own block holds their entries):
  // large enough that the trailing block factors, then subtracted from the Schur complement.
  // The rounding error of that subtraction is ~1e-16 kappa, far below the smallest shift the
  // proof tries (1e-13 max diag Q, dual_bound.hpp).
  double kappa = 1.0;
  for (Eigen::Index k = 0; k < A.outerSize(); ++k)
    for (SparseMatrix::InnerIterator it(A, k); it; ++it)
      if (it.row() == k) kappa = std::max(kappa, 4.0 * std::abs(it.value()));
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(A.nonZeros() + n + nF));
  for (Eigen::Index col = 0; col < n; ++col) {
    const Eigen::Index pc = pos[static_cast<std::size_t>(col)];
    for (SparseMatrix::InnerIterator it(A, col); it; ++it) {
      const Eigen::Index pr = pos[static_cast<std::size_t>(it.row())];
      if (pr >= pc) t.emplace_back(pr, pc, it.value());
    }
    t.emplace_back(pc, pc, shift(col));
    if (nF > 0 && !is_kept[static_cast<std::size_t>(col / w)])
      for (SparseMatrix::InnerIterator it(Qnb, col); it; ++it)
        if (it.value() != 0.0)
          t.emplace_back(foreign_pos[static_cast<std::size_t>(it.row())], pc, it.value());
  }
  const std::size_t placeholder = t.size();
  for (Eigen::Index c = n; c < n + nF; ++c) t.emplace_back(c, c, kappa);
  const Eigen::Index total = n + nF;
  if (total == 0) {
    out.positive_definite = true;
    return out;
  }
  for (int attempt = 0;; ++attempt) {
    SparseMatrix B(total, total);
    B.setFromTriplets(t.begin(), t.end());
    SupernodalCholesky llt(CHOLMOD_NATURAL);
    const Eigen::Index failed = llt.factor(B);
    if (failed < n) return out;  // a principal submatrix of S + D is not PD
    if (failed == total) {
      out.positive_definite = true;
      const Eigen::MatrixXd Lgg = llt.trailing_block(nI);
      out.schur = lower_times_transpose(Lgg);
      for (Eigen::Index c = nK; c < nG; ++c) out.schur(c, c) -= kappa;
      break;
    }
    if (attempt == 30) throw std::runtime_error("certificate: no placeholder factored");
    kappa *= 16.0;  // the placeholder was too small
    for (std::size_t k = placeholder; k < t.size(); ++k)
      t[k] = Eigen::Triplet<double>(t[k].row(), t[k].col(), kappa);
  }

  // The cut measurements' coupling between separator poses: S's entries there are Q's (Lambda
  // is pose-diagonal), each pair once, sent by the owner of the smaller id.
  for (Eigen::Index col = 0; col < n; ++col) {
    if (!is_kept[static_cast<std::size_t>(col / w)]) continue;
    const std::size_t own = owned[static_cast<std::size_t>(col / w)];
    for (SparseMatrix::InnerIterator it(Qnb, col); it; ++it) {
      const std::size_t other = neighbors[static_cast<std::size_t>(it.row() / w)];
      if (own > other || it.value() == 0.0 || !in_separator(other)) continue;
      out.rows.push_back(static_cast<Eigen::Index>(own) * w + col % w);
      out.cols.push_back(static_cast<Eigen::Index>(other) * w + it.row() % w);
      out.values.push_back(it.value());
    }
  }
  return out;
}

std::vector<double> encode_interface_schur(const InterfaceSchurBlock& block) {
  std::vector<double> v;
  const Eigen::Index m = block.schur.rows();
  v.push_back(block.positive_definite ? 1.0 : 0.0);
  v.push_back(static_cast<double>(block.poses.size()));
  for (std::size_t p : block.poses) v.push_back(static_cast<double>(p));
  v.push_back(static_cast<double>(m));
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index i = j; i < m; ++i) v.push_back(block.schur(i, j));
  v.push_back(static_cast<double>(block.values.size()));
  for (std::size_t k = 0; k < block.values.size(); ++k) {
    v.push_back(static_cast<double>(block.rows[k]));
    v.push_back(static_cast<double>(block.cols[k]));
    v.push_back(block.values[k]);
  }
  return v;
}

InterfaceSchurBlock decode_interface_schur(const std::vector<double>& v) {
  auto fail = [] { throw std::runtime_error("certificate: malformed interface block"); };
  std::size_t at = 0;
  auto next = [&]() {
    if (at >= v.size()) fail();
    return v[at++];
  };
  auto count = [&]() {
    const double x = next();
    if (!(x >= 0) || x > static_cast<double>(v.size())) fail();
    return static_cast<std::size_t>(x);
  };
  InterfaceSchurBlock b;
  b.positive_definite = next() != 0.0;
  b.poses.resize(count());
  for (auto& p : b.poses) p = static_cast<std::size_t>(next());
  const auto m = static_cast<Eigen::Index>(count());
  b.schur.resize(m, m);
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index i = j; i < m; ++i) b.schur(i, j) = b.schur(j, i) = next();
  const std::size_t k = count();
  for (std::size_t e = 0; e < k; ++e) {
    b.rows.push_back(static_cast<Eigen::Index>(next()));
    b.cols.push_back(static_cast<Eigen::Index>(next()));
    b.values.push_back(next());
  }
  if (at != v.size()) fail();
  return b;
}

bool interface_positive_definite(const std::vector<InterfaceSchurBlock>& blocks, int d) {
  const Eigen::Index w = d + 1;
  std::unordered_map<std::size_t, Eigen::Index> index;  // pose -> first coordinate in Sigma
  Eigen::Index M = 0;
  for (const auto& b : blocks) {
    if (!b.positive_definite) return false;
    if (b.schur.rows() != w * static_cast<Eigen::Index>(b.poses.size()))
      throw std::runtime_error("certificate: interface block of the wrong size");
    for (std::size_t p : b.poses)              // a separator pose is in its owner's share and its
      if (index.emplace(p, M).second) M += w;  // neighbours' (their Schur complements add up)
  }
  if (M == 0) return true;
  // Sparse: Sigma is dense only within each block's interface; the cut couples few entries
  // (city10000 at N = 5: 152k factor entries against 414k for the dense lower triangle).
  std::vector<Eigen::Triplet<double>> t;
  for (const auto& b : blocks) {
    std::vector<Eigen::Index> at(b.poses.size());  // Sigma's coordinate of each pose's first
    for (std::size_t k = 0; k < b.poses.size(); ++k) at[k] = index.at(b.poses[k]);
    for (Eigen::Index j = 0; j < b.schur.cols(); ++j)
      for (Eigen::Index i = j; i < b.schur.rows(); ++i) {
        const Eigen::Index r = at[static_cast<std::size_t>(i / w)] + i % w;
        const Eigen::Index c = at[static_cast<std::size_t>(j / w)] + j % w;
        t.emplace_back(std::max(r, c), std::min(r, c), b.schur(i, j));
      }
  }
  for (const auto& b : blocks)
    for (std::size_t k = 0; k < b.values.size(); ++k) {
      auto ri = index.find(static_cast<std::size_t>(b.rows[k] / w));
      auto ci = index.find(static_cast<std::size_t>(b.cols[k] / w));
      if (ri == index.end() || ci == index.end())
        throw std::runtime_error("certificate: coupling outside the interface");
      const Eigen::Index r = ri->second + b.rows[k] % w, c = ci->second + b.cols[k] % w;
      t.emplace_back(std::max(r, c), std::min(r, c), b.values[k]);
    }
  SparseMatrix sigma(M, M);
  sigma.setFromTriplets(t.begin(), t.end());
  SupernodalCholesky llt(CHOLMOD_AMD);
  return llt.factor(sigma) == M;
}

}  // namespace tessera
