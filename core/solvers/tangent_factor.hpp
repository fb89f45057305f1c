#pragma once
// The tangent preconditioner's factor storage: A's pattern and values, its CHOLMOD factor with
// solve workspace, and the grown poses' appended block (tangent_factor_growth.cpp). Shared by
// the preconditioner's construction and apply (tangent_preconditioner.cpp) and by grow().

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <vector>

#include "solvers/cholmod_checked.hpp"
#include "solvers/cholmod_dense_view.hpp"
#include "solvers/ldl_chain_solve.hpp"

namespace tessera {

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

struct TangentPreconditioner::Factor {
  ~Factor() {
    cholmod_common& c = llt.cholmod();
    for (cholmod_dense** x : {&solve_x, &solve_y, &solve_e})
      if (*x) cholmod_free_dense(x, &c);
  }
  // A^{-1} b for the right-hand side in `b`; the result is valid until the next call. The same
  // numeric solve as CholmodDecomposition::solve (cholmod_solve calls
  // cholmod_solve2 with fresh workspace), hence the same result.
  const double* solve() {
    if (chain.ready()) {
      solution.resize(b.size());
      chain.solve(llt.factor(), b.data(), solution.data());
      return solution.data();
    }
    cholmod_dense rhs = cholmod_dense_view(b);
    cholmod_common& c = llt.cholmod();
    if (!cholmod_solve2(CHOLMOD_A, llt.factor(), &rhs, nullptr, &solve_x, nullptr, &solve_y,
                        &solve_e, &c))
      throw_cholmod_failure("TangentPreconditioner", "solve", c.status, static_cast<long>(b.size()),
                            static_cast<long>(b.size()));
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
  // A's lower block triangle (every pose-block pair i >= j p x p dense, the diagonal blocks
  // whole; CHOLMOD reads the lower half).
  SparseMatrix A;
  CholmodLdlt llt;
  // Solve workspace, reused by every apply (agents apply their own preconditioner only).
  Eigen::VectorXd b;
  cholmod_dense *solve_x = nullptr, *solve_y = nullptr, *solve_e = nullptr;
  // The same solve with a simplicial factor, fewer instructions (ldl_chain_solve.hpp); indexed
  // after every factorization.
  LdlChainSolve chain;
  Eigen::VectorXd solution;
  std::size_t entries = 0;
  double flops = 0.0;
  bool supernodal = false;
  // Supernodal factorizations converted to simplicial LDL^T for the solves (`simplicial_solves`):
  // `order` is the simplicial analysis' permutation, which each supernodal analysis is given.
  bool convert = false;
  std::vector<int> order;

  // The supernodal symbolic analysis of A with `order` (a converted factor is simplicial, and
  // CHOLMOD factors supernodally only with a supernodal symbolic factor). False when it fails.
  bool analyze_supernodal() {
    llt.setMode(Eigen::CholmodSupernodalLLt);
    llt.cholmod().postorder = 1;
    llt.analyze_with_ordering(A, order);
    return llt.info() == Eigen::Success && !cholmod_analysis_failed(llt);
  }
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

  // Offset in A's value array of entry (0, c) of the block in slot s (>= diagonal_slot[j]) of
  // block column j.
  Eigen::Index value_offset(Eigen::Index j, Eigen::Index s, int c) const {
    return A.outerIndexPtr()[j * p + c] + (s - diagonal_slot[static_cast<std::size_t>(j)]) * p;
  }
};

}  // namespace tessera
