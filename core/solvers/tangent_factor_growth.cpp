// TangentPreconditioner::grow(): a block's new poses appended to the held factor as a block
// LDL^T (the online engine's --refactor-growth), apart from construction and factorization.
#include <Eigen/Dense>
#include <algorithm>
#include <map>
#include <memory>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <utility>
#include <vector>

#include "solvers/tangent_coordinates.hpp"
#include "solvers/tangent_factor.hpp"

namespace tessera {

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

}  // namespace tessera
