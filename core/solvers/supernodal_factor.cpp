#include "solvers/supernodal_factor.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "solvers/cholmod_checked.hpp"
#include "solvers/cholmod_dense_view.hpp"
#include "solvers/triplet_scatter.hpp"
#include "util/serial_blas.hpp"

namespace tessera {

struct SupernodalFactor::Impl {
  explicit Impl(Ordering o) : ordering(o) {
    cholmod_start(&c);
    c.print = 0;  // not positive definite is an answer here, not an error to print
    c.supernodal = CHOLMOD_SUPERNODAL;
    c.final_ll = 1;
    c.nmethods = 1;
    c.method[0].ordering = o == Ordering::kAmd ? CHOLMOD_AMD : CHOLMOD_NATURAL;
    c.postorder = o == Ordering::kAmd ? 1 : 0;
  }
  ~Impl() {
    for (cholmod_dense** x : {&x_, &y_, &e_})
      if (*x) cholmod_free_dense(x, &c);
    if (L) cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
  }
  Ordering ordering;
  mutable cholmod_common c;  // the solves' workspace and status live here
  cholmod_factor* L = nullptr;
  // The analysed pattern.
  Eigen::Index n = -1;
  std::vector<int> outer, inner;
  bool ok = false;
  int analyses = 0;
  std::size_t entries = 0;
  double flops = 0.0;
  mutable cholmod_dense *x_ = nullptr, *y_ = nullptr, *e_ = nullptr;
  // kAmd: the analysis' permutation (AMD, postordered), held here rather than by the factor.
  // CHOLMOD permutes a lower-triangle input with two transposes at every factorization (Sigma
  // on city10000: 7 M instructions each, beside 16 M of numeric work); here the lower
  // triangle of A(P, P) is written through a map laid out at the analysis, and the factor,
  // told its input comes permuted (natural ordering), factors that same matrix: the same
  // supernodes, values and factor to the bit. The solves apply P around L's.
  std::vector<int> perm;
  TripletScatter permuted;
  mutable Eigen::VectorXd scratch;
  void take_permutation(const SparseMatrix& lower);
};

// After a kAmd analysis: moves the factor's permutation P into s.perm, lays out the lower
// triangle of lower(P, P) (s.permuted) and marks the factor as taking its input in that order
// (natural ordering, identity Perm). Where the layout fails, s.perm stays empty and the factor
// untouched.
void SupernodalFactor::Impl::take_permutation(const SparseMatrix& lower) {
  Impl& s = *this;
  cholmod_factor* L = s.L;
  const auto n = static_cast<Eigen::Index>(L->n);
  if (!L->Perm || L->ordering == CHOLMOD_NATURAL) return;
  const int* P = static_cast<const int*>(L->Perm);
  std::vector<int> inverse(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k)
    inverse[static_cast<std::size_t>(P[k])] = static_cast<int>(k);
  std::vector<int> rows, cols;
  rows.reserve(static_cast<std::size_t>(lower.nonZeros()));
  cols.reserve(static_cast<std::size_t>(lower.nonZeros()));
  for (Eigen::Index j = 0; j < n; ++j)
    for (SparseMatrix::InnerIterator it(lower, j); it; ++it) {
      if (it.row() < j) return;  // CHOLMOD reads the lower triangle only
      const int a = inverse[static_cast<std::size_t>(it.row())];
      const int b = inverse[static_cast<std::size_t>(j)];
      rows.push_back(std::max(a, b));
      cols.push_back(std::min(a, b));
    }
  if (!s.permuted.build(n, rows, cols)) return;
  s.perm.assign(P, P + n);
  int* perm = static_cast<int*>(L->Perm);
  for (Eigen::Index k = 0; k < n; ++k) perm[k] = static_cast<int>(k);
  if (L->IPerm) {
    int* iperm = static_cast<int*>(L->IPerm);
    for (Eigen::Index k = 0; k < n; ++k) iperm[k] = static_cast<int>(k);
  }
  L->ordering = CHOLMOD_NATURAL;
}

SupernodalFactor::SupernodalFactor(Ordering ordering) : impl_(std::make_unique<Impl>(ordering)) {}
SupernodalFactor::~SupernodalFactor() = default;

bool SupernodalFactor::factor(const SparseMatrix& lower, double shift) {
  Impl& s = *impl_;
  s.ok = false;
  if (lower.rows() != lower.cols() || !lower.isCompressed())
    throw std::invalid_argument("SupernodalFactor: not a square compressed matrix");
  const Eigen::Index n = lower.rows();
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  const auto nnz = static_cast<std::size_t>(lower.nonZeros());
  cholmod_sparse a = Eigen::viewAsCholmod(lower.selfadjointView<Eigen::Lower>());
  const bool same = s.L && n == s.n && std::equal(outer, outer + n + 1, s.outer.begin()) &&
                    s.inner.size() == nnz && std::equal(inner, inner + nnz, s.inner.begin());
  if (!same) {
    if (s.L) cholmod_free_factor(&s.L, &s.c);
    s.L = cholmod_analyze(&a, &s.c);
    if (!s.L) throw_cholmod_failure("SupernodalFactor", "analysis", s.c.status, n, n);
    ++s.analyses;
    s.n = n;
    s.outer.assign(outer, outer + n + 1);
    s.inner.assign(inner, inner + nnz);
    s.entries = static_cast<std::size_t>(s.c.lnz);
    s.flops = s.c.fl;
    s.perm.clear();
    // Where the layout fails (perm stays empty), CHOLMOD's own permuted path: the same factor.
    if (s.ordering == Ordering::kAmd) s.take_permutation(lower);
  }
  double beta[2] = {shift, 0.0};
  if (!s.perm.empty()) {
    s.permuted.fill(lower.valuePtr(), nnz);
    cholmod_sparse pa = Eigen::viewAsCholmod(s.permuted.matrix().selfadjointView<Eigen::Lower>());
    const SerialBlasLock lock(serial_blas_mutex());
    cholmod_factorize_p(&pa, beta, nullptr, 0, s.L, &s.c);
  } else {
    const SerialBlasLock lock(serial_blas_mutex());
    cholmod_factorize_p(&a, beta, nullptr, 0, s.L, &s.c);
  }
  if (s.c.status < CHOLMOD_OK)
    throw_cholmod_failure("SupernodalFactor", "factorization", s.c.status, n, n);
  s.ok = s.c.status == CHOLMOD_OK && s.L->minor == s.L->n;
  return s.ok;
}

bool SupernodalFactor::ok() const {
  return impl_->ok;
}

void SupernodalFactor::solve_system(int system, Eigen::VectorXd& v) const {
  const Impl& s = *impl_;
  if (!s.ok) throw std::logic_error("SupernodalFactor: no positive definite factor");
  if (v.size() != s.n) throw std::invalid_argument("SupernodalFactor: wrong vector size");
  if (system != CHOLMOD_A && s.ordering != Ordering::kGiven)
    throw std::logic_error("SupernodalFactor: L solves need the given ordering");
  cholmod_dense rhs = cholmod_dense_view(v);
  const SerialBlasLock lock(serial_blas_mutex());
  if (!cholmod_solve2(system, s.L, &rhs, nullptr, &s.x_, nullptr, &s.y_, &s.e_, &s.c))
    throw_cholmod_failure("SupernodalFactor", "solve", s.c.status, s.n, s.n);
  v = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(s.x_->x), v.size());
}

void SupernodalFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  const Impl& s = *impl_;
  if (s.perm.empty()) {
    x = b;
    solve_system(CHOLMOD_A, x);
    return;
  }
  // P b, L's solves, P^T: the copies CHOLMOD's solve makes with its own permutation.
  if (b.size() != static_cast<Eigen::Index>(s.perm.size()))
    throw std::invalid_argument("SupernodalFactor: wrong vector size");
  s.scratch.resize(b.size());
  for (std::size_t k = 0; k < s.perm.size(); ++k)
    s.scratch(static_cast<Eigen::Index>(k)) = b(s.perm[k]);
  solve_system(CHOLMOD_A, s.scratch);
  x.resize(b.size());
  for (std::size_t k = 0; k < s.perm.size(); ++k)
    x(s.perm[k]) = s.scratch(static_cast<Eigen::Index>(k));
}

void SupernodalFactor::solve_l(Eigen::VectorXd& v) const {
  solve_system(CHOLMOD_L, v);
}

void SupernodalFactor::solve_lt(Eigen::VectorXd& v) const {
  solve_system(CHOLMOD_Lt, v);
}

Eigen::MatrixXd SupernodalFactor::trailing_block(Eigen::Index first) const {
  const Impl& s = *impl_;
  if (!s.ok) throw std::logic_error("SupernodalFactor: no positive definite factor");
  if (s.ordering != Ordering::kGiven)
    throw std::logic_error("SupernodalFactor: the trailing block needs the given ordering");
  const cholmod_factor* L = s.L;
  const auto n = static_cast<Eigen::Index>(L->n);
  if (first < 0 || first > n) throw std::invalid_argument("SupernodalFactor: bad first column");
  const int* perm = static_cast<const int*>(L->Perm);
  for (Eigen::Index k = first; k < n; ++k)
    if (perm && perm[k] != k) throw std::logic_error("SupernodalFactor: the factor was reordered");
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n - first, n - first);
  if (!L->is_super) throw std::logic_error("SupernodalFactor: not a supernodal factor");
  const int* super = static_cast<const int*>(L->super);
  const int* pi = static_cast<const int*>(L->pi);
  const int* px = static_cast<const int*>(L->px);
  const int* rows = static_cast<const int*>(L->s);
  const double* x = static_cast<const double*>(L->x);
  for (std::size_t k = 0; k < L->nsuper; ++k) {
    const int c0 = super[k], c1 = super[k + 1], nr = pi[k + 1] - pi[k];
    if (c1 <= first) continue;
    for (int j = std::max<int>(c0, static_cast<int>(first)); j < c1; ++j)
      for (int r = j - c0; r < nr; ++r) {
        const int i = rows[pi[k] + r];
        out(i - first, j - first) = x[px[k] + static_cast<std::ptrdiff_t>(j - c0) * nr + r];
      }
  }
  return out;
}

namespace {

// Each supernode's columns from its diagonal down (its values are column-major, nr rows per
// column; the diagonal block's upper triangle is not part of L and is never read by the solves).
template <class Visit>
void for_each_factor_column(const cholmod_factor& L, Visit visit) {
  const int* super = static_cast<const int*>(L.super);
  const int* pi = static_cast<const int*>(L.pi);
  const int* px = static_cast<const int*>(L.px);
  for (std::size_t k = 0; k < L.nsuper; ++k) {
    const int nc = super[k + 1] - super[k], nr = pi[k + 1] - pi[k];
    for (int j = 0; j < nc; ++j)
      visit(static_cast<std::size_t>(px[k]) + static_cast<std::size_t>(j) * nr + j,
            static_cast<std::size_t>(nr - j));
  }
}

}  // namespace

std::vector<double> SupernodalFactor::values() const {
  const Impl& s = *impl_;
  if (!s.ok || !s.L->is_super || !s.L->x) return {};
  const double* x = static_cast<const double*>(s.L->x);
  std::vector<double> out;
  for_each_factor_column(*s.L, [&](std::size_t at, std::size_t count) {
    out.insert(out.end(), x + at, x + at + count);
  });
  return out;
}

bool SupernodalFactor::import_values(const double* x, std::size_t count) {
  Impl& s = *impl_;
  if (!s.L || !s.L->is_super || s.L->xtype != CHOLMOD_REAL || !s.L->x) return false;
  std::size_t total = 0;
  for_each_factor_column(*s.L, [&](std::size_t, std::size_t n) { total += n; });
  if (total != count) return false;
  double* to = static_cast<double*>(s.L->x);
  std::size_t from = 0;
  for_each_factor_column(*s.L, [&](std::size_t at, std::size_t n) {
    std::copy_n(x + from, n, to + at);
    from += n;
  });
  s.L->minor = s.L->n;  // a factor that stopped at a pivot holds a complete one now
  s.ok = true;
  return true;
}

void SupernodalFactor::adopt_analysis(const SupernodalFactor& other) {
  Impl& s = *impl_;
  const Impl& o = *other.impl_;
  if (o.ordering != s.ordering)
    throw std::invalid_argument("SupernodalFactor::adopt_analysis: another ordering");
  if (s.L) cholmod_free_factor(&s.L, &s.c);
  s.ok = false;
  s.n = -1;
  s.perm.clear();
  if (!o.L) return;
  s.L = cholmod_copy_factor(o.L, &s.c);
  if (!s.L) throw_cholmod_failure("SupernodalFactor", "copy", s.c.status, o.n, o.n);
  s.n = o.n;
  s.outer = o.outer;
  s.inner = o.inner;
  s.entries = o.entries;
  s.flops = o.flops;
  s.perm = o.perm;
  s.permuted = o.permuted;
}

int SupernodalFactor::analyses() const {
  return impl_->analyses;
}
std::size_t SupernodalFactor::factor_entries() const {
  return impl_->entries;
}
double SupernodalFactor::factor_flops() const {
  return impl_->flops;
}

}  // namespace tessera
