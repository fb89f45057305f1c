#include "distributed/translation_interface_solve.hpp"

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "distributed/interface_poses.hpp"
#include "distributed/schur_share.hpp"
#include "distributed/team_interface.hpp"
#include "solvers/interface_last_order.hpp"

namespace tessera {

Eigen::Index interface_pose_count(const BlockLayout& layout) {
  Eigen::Index poses = 0;
  for (int b = 0; b < layout.num_blocks; ++b)
    poses += static_cast<Eigen::Index>(interface_poses(layout, b).size());
  return poses;
}

struct TranslationInterfaceSolve::Impl {
  Eigen::Index m = 0, mI = 0, mG = 0;         // poses: all, interior, interface
  std::vector<Eigen::Index> slot;             // local pose -> position in the factor's order
  std::vector<Eigen::Index> interface_local;  // the own interface poses' local indices
  std::vector<Coupling> cut;                  // own < other
  TeamInterface team;                         // the team's interface in Sigma, one row a pose
  Eigen::Index own_offset = 0;
  // L_BB = L D L^T in the order above; L's trailing interface block; D's interior inverse.
  Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::NaturalOrdering<int>> ldlt;
  bool block_ok = false;
  Eigen::MatrixXd Lgg;
  Eigen::VectorXd Dinv_interior;
  // Sigma with the team's first interface pose held fixed (grounded), else Sigma + eta I.
  Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower> sigma;
  bool sigma_ok = false, grounded = false;
};

TranslationInterfaceSolve::TranslationInterfaceSolve(const BlockProblem& problem,
                                                     const BlockLayout& layout, int id)
    : impl_(std::make_unique<Impl>()) {
  const Eigen::Index w = problem.dim() + 1;
  const std::vector<std::size_t>& owned = problem.owned();
  const std::vector<std::size_t>& neighbors = problem.neighbors();

  // L_BB: Q_BB's translation-translation entries (each pose's last column).
  const SparseMatrix& Q = problem.data_matrix();
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index c = w - 1; c < Q.outerSize(); c += w)
    for (SparseMatrix::InnerIterator it(Q, c); it; ++it)
      if (it.row() % w == w - 1) entries.emplace_back(it.row() / w, c / w, it.value());

  // The cut's couplings: L(i, j) for own i and neighbour j, from Q_NB's (j, i) entry.
  const SparseMatrix& Qnb = problem.neighbor_matrix();
  std::vector<Coupling> cut;
  for (Eigen::Index c = w - 1; c < Qnb.outerSize(); c += w)
    for (SparseMatrix::InnerIterator it(Qnb, c); it; ++it) {
      if (it.row() % w != w - 1 || it.value() == 0.0) continue;
      cut.push_back({owned[static_cast<std::size_t>(c / w)],
                     neighbors[static_cast<std::size_t>(it.row() / w)], it.value()});
    }
  set_up(owned, entries, cut, layout, id);
}

TranslationInterfaceSolve::TranslationInterfaceSolve(
    const std::vector<std::size_t>& owned, const std::vector<Eigen::Triplet<double>>& entries,
    const std::vector<Coupling>& cut, const BlockLayout& layout, int id)
    : impl_(std::make_unique<Impl>()) {
  set_up(owned, entries, cut, layout, id);
}

void TranslationInterfaceSolve::set_up(const std::vector<std::size_t>& owned,
                                       const std::vector<Eigen::Triplet<double>>& entries,
                                       const std::vector<Coupling>& cut, const BlockLayout& layout,
                                       int id) {
  Impl& s = *impl_;
  s.m = static_cast<Eigen::Index>(owned.size());
  s.team = team_interface(layout, 1);
  s.own_offset = s.team.block_offset.at(static_cast<std::size_t>(id));
  OwnInterfaceLast own = own_interface_last(owned, layout, id, "TranslationInterfaceSolve");
  s.slot = std::move(own.slot);
  s.interface_local = std::move(own.local);
  s.mI = own.interior;
  s.mG = s.m - s.mI;

  // Interior poses first (fill-reducing order), the interface's last.
  place_interior_first(s.slot, [&](const auto& add) {
    for (const auto& e : entries) add(e.row(), e.col());
  });

  std::vector<Eigen::Triplet<double>> lower;
  for (const auto& e : entries) {
    const Eigen::Index a = s.slot[static_cast<std::size_t>(e.row())];
    const Eigen::Index c = s.slot[static_cast<std::size_t>(e.col())];
    if (a >= c) lower.emplace_back(a, c, e.value());
  }
  SparseMatrix A(s.m, s.m);
  A.setFromTriplets(lower.begin(), lower.end());
  s.ldlt.compute(A);
  s.block_ok = s.m > 0 && s.ldlt.info() == Eigen::Success && (s.ldlt.vectorD().array() > 0).all() &&
               s.ldlt.vectorD().allFinite();
  if (s.block_ok) {
    s.Dinv_interior = s.ldlt.vectorD().head(s.mI).cwiseInverse();
    s.Lgg = Eigen::MatrixXd::Identity(s.mG, s.mG);
    const auto& L = s.ldlt.matrixL().nestedExpression();
    for (Eigen::Index c = s.mI; c < s.m; ++c)
      for (std::remove_reference_t<decltype(L)>::InnerIterator it(L, c); it; ++it)
        if (it.row() > c) s.Lgg(it.row() - s.mI, c - s.mI) = it.value();
  }

  // The block with the smaller pose id reports a coupling; one between poses outside the
  // layout's interface cannot be placed in Sigma: the block says so in its share.
  for (const Coupling& c : cut) {
    if (c.own >= c.other) continue;
    if (s.team.first.count(c.own) == 0 || s.team.first.count(c.other) == 0) s.block_ok = false;
    s.cut.push_back(c);
  }
}

TranslationInterfaceSolve::~TranslationInterfaceSolve() = default;

Eigen::Index TranslationInterfaceSolve::team_size() const {
  return impl_->team.size;
}
Eigen::Index TranslationInterfaceSolve::offset() const {
  return impl_->own_offset;
}
Eigen::Index TranslationInterfaceSolve::size() const {
  return impl_->mG;
}
Eigen::Index TranslationInterfaceSolve::block_offset(int b) const {
  return impl_->team.block_offset.at(static_cast<std::size_t>(b));
}
Eigen::Index TranslationInterfaceSolve::block_size(int b) const {
  return impl_->team.block_size.at(static_cast<std::size_t>(b));
}
Eigen::Index TranslationInterfaceSolve::team_row(std::size_t pose) const {
  auto it = impl_->team.first.find(pose);
  return it == impl_->team.first.end() ? -1 : it->second;
}
bool TranslationInterfaceSolve::ready() const {
  return impl_->sigma_ok;
}

std::vector<double> TranslationInterfaceSolve::share() const {
  const Impl& s = *impl_;
  if (!s.block_ok) return {0.0};
  const Eigen::MatrixXd schur =
      s.Lgg * s.ldlt.vectorD().tail(s.mG).asDiagonal() * s.Lgg.transpose();
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(2 + s.mG * (s.mG + 1) / 2) + 3 * s.cut.size());
  out.push_back(1.0);
  for (Eigen::Index j = 0; j < s.mG; ++j)
    for (Eigen::Index i = j; i < s.mG; ++i) out.push_back(0.5 * (schur(i, j) + schur(j, i)));
  out.push_back(static_cast<double>(s.cut.size()));
  for (const Coupling& c : s.cut) {
    out.push_back(static_cast<double>(c.own));
    out.push_back(static_cast<double>(c.other));
    out.push_back(c.value);
  }
  return out;
}

bool TranslationInterfaceSolve::assemble(const std::vector<const std::vector<double>*>& blocks,
                                         bool factor) {
  Impl& s = *impl_;
  s.sigma_ok = false;
  if (blocks.size() != s.team.block_offset.size())
    throw std::runtime_error("translation interface solve: shares from the wrong number of agents");
  std::vector<Eigen::Triplet<double>> t;
  double top = 0.0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const std::vector<double>& v = *blocks[b];
    auto fail = [b] {
      throw std::runtime_error("translation interface solve: malformed share from agent " +
                               std::to_string(b));
    };
    std::size_t k = 0;
    if (!read_schur_triangle(v, s.team.block_offset[b], s.team.block_size[b], t, top, k, fail))
      return false;  // that block's L_BB is not positive definite
    const double count = v[k++];
    if (!(count >= 0) || v.size() != k + 3 * static_cast<std::size_t>(count)) fail();
    for (; k < v.size(); k += 3) {
      const Eigen::Index r = team_row(static_cast<std::size_t>(v[k]));
      const Eigen::Index c = team_row(static_cast<std::size_t>(v[k + 1]));
      if (r < 0 || c < 0) fail();
      t.emplace_back(std::max(r, c), std::min(r, c), v[k + 2]);
    }
  }
  if (s.team.size == 0) return false;
  if (!factor) return true;
  // Grounded: the first interface pose's row and column dropped (the constants are Sigma's
  // kernel on a connected graph, so the rest is positive definite and solved exactly).
  if (s.team.size > 1) {
    std::vector<Eigen::Triplet<double>> g;
    g.reserve(t.size());
    for (const auto& e : t)
      if (e.row() > 0 && e.col() > 0) g.emplace_back(e.row() - 1, e.col() - 1, e.value());
    SparseMatrix reduced(s.team.size - 1, s.team.size - 1);
    reduced.setFromTriplets(g.begin(), g.end());
    s.sigma.compute(reduced);
    if (s.sigma.info() == Eigen::Success) {
      s.sigma_ok = s.grounded = true;
      return true;
    }
  }
  SparseMatrix sigma(s.team.size, s.team.size);
  sigma.setFromTriplets(t.begin(), t.end());
  SparseMatrix I(s.team.size, s.team.size);
  I.setIdentity();
  s.sigma.compute(sigma + 1e-10 * std::max(top, 1e-300) * I);
  s.grounded = false;
  s.sigma_ok = s.sigma.info() == Eigen::Success;
  return s.sigma_ok;
}

void TranslationInterfaceSolve::forward(const Eigen::MatrixXd& b, Eigen::MatrixXd& y) const {
  const Impl& s = *impl_;
  if (!s.block_ok) throw std::logic_error("TranslationInterfaceSolve::forward: no block factor");
  if (b.rows() != s.m) throw std::invalid_argument("TranslationInterfaceSolve::forward: rows");
  y.resize(s.m, b.cols());
  for (Eigen::Index i = 0; i < s.m; ++i) y.row(s.slot[static_cast<std::size_t>(i)]) = b.row(i);
  s.ldlt.matrixL().solveInPlace(y);
}

Eigen::MatrixXd TranslationInterfaceSolve::interface_residual(const Eigen::MatrixXd& y) const {
  const Impl& s = *impl_;
  return s.Lgg * y.bottomRows(s.mG);
}

Eigen::MatrixXd TranslationInterfaceSolve::solve_interface(const Eigen::MatrixXd& rhat) const {
  const Impl& s = *impl_;
  if (!s.sigma_ok) throw std::logic_error("TranslationInterfaceSolve: no factor of Sigma");
  if (!s.grounded) return s.sigma.solve(rhat);
  Eigen::MatrixXd u(s.team.size, rhat.cols());
  u.row(0).setZero();
  u.bottomRows(s.team.size - 1) = s.sigma.solve(rhat.bottomRows(s.team.size - 1));
  return u;
}

Eigen::MatrixXd TranslationInterfaceSolve::back(const Eigen::MatrixXd& y,
                                                const Eigen::MatrixXd& u) const {
  const Impl& s = *impl_;
  const Eigen::MatrixXd uG = u.middleRows(s.own_offset, s.mG);
  Eigen::MatrixXd v(s.m, y.cols());
  v.topRows(s.mI) = s.Dinv_interior.asDiagonal() * y.topRows(s.mI);
  v.bottomRows(s.mG) = s.Lgg.transpose() * uG;
  s.ldlt.matrixU().solveInPlace(v);
  Eigen::MatrixXd x(s.m, y.cols());
  for (Eigen::Index i = 0; i < s.m; ++i) x.row(i) = v.row(s.slot[static_cast<std::size_t>(i)]);
  // The interface rows are u's, as every other agent takes them.
  for (Eigen::Index k = 0; k < s.mG; ++k)
    x.row(s.interface_local[static_cast<std::size_t>(k)]) = uG.row(k);
  return x;
}

}  // namespace tessera
