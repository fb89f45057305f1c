#include "distributed/interface_solve.hpp"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <array>
#include <stdexcept>
#include <unordered_map>

#include "distributed/interface_poses.hpp"
#include "distributed/schur_share.hpp"
#include "distributed/team_interface.hpp"
#include "solvers/interface_last_order.hpp"
#include "solvers/supernodal_factor.hpp"
#include "solvers/tangent_coordinates.hpp"
#include "solvers/triplet_scatter.hpp"

namespace tessera {

namespace {

// One pose pair's (d+1) x (d+1) block of Q, column-major (rows: pose i's coordinates), in a
// fixed array (d <= 3): no heap block per pair (a city10000 block has ~10,000 pairs).
struct PosePair {
  Eigen::Index i = 0, j = 0;
  std::array<double, 16> q{};
};

}  // namespace

Eigen::Index interface_tangent_coordinates(const BlockLayout& layout, int dim) {
  Eigen::Index poses = 0;
  for (int b = 0; b < layout.num_blocks; ++b)
    poses += static_cast<Eigen::Index>(interface_poses(layout, b).size());
  return poses * dim * (dim + 1) / 2;
}

bool interface_fits(const NewtonRefineOptions& r, const BlockLayout& layout, int dim) {
  if (!r.enabled || r.when != NewtonRefineOptions::When::kIfRoundsSlow ||
      !(r.auto_interface_grad_tol > 0) || r.interface_max_coordinates <= 0 ||
      r.coarse != NewtonRefineOptions::Coarse::kNone || layout.num_blocks <= 1)
    return false;
  const Eigen::Index size = interface_tangent_coordinates(layout, dim);
  return size > 0 && size <= r.interface_max_coordinates;
}

struct InterfaceFactors {
  // The block's factor A_bb = L L^T in the order below, and the same at a trial point
  // (factor_pending), the current one's until commit_pending() (both patterns are the same at
  // every point: one analysis each).
  std::unique_ptr<SupernodalFactor> block =
      std::make_unique<SupernodalFactor>(SupernodalFactor::Ordering::kGiven);
  std::unique_ptr<SupernodalFactor> pending;
  // Sigma + eta I, not grounded and grounded: two patterns, so two analyses that a point which
  // falls back from one to the other keeps.
  SupernodalFactor sigma[2];
  // The block's Hessian A_bb (lower triangle, the order below) and Sigma (not grounded,
  // grounded), as positions laid out once and values written at each point
  // (solvers/triplet_scatter.hpp).
  TripletScatter block_pattern, sigma_pattern[2];
  // Analyses run by the factors above so far.
  int analyses() const {
    return block->analyses() + (pending ? pending->analyses() : 0) + sigma[0].analyses() +
           sigma[1].analyses();
  }
};

InterfaceAnalysisStore::InterfaceAnalysisStore() = default;
InterfaceAnalysisStore::~InterfaceAnalysisStore() = default;

std::unique_ptr<InterfaceFactors> InterfaceAnalysisStore::take(int id) {
  const std::lock_guard<std::mutex> lock(mutex_);
  auto it = held_.find(id);
  if (it == held_.end() || !it->second) return std::make_unique<InterfaceFactors>();
  std::unique_ptr<InterfaceFactors> out = std::move(it->second);
  held_.erase(it);
  return out;
}

void InterfaceAnalysisStore::give(int id, std::unique_ptr<InterfaceFactors> factors) {
  const std::lock_guard<std::mutex> lock(mutex_);
  held_[id] = std::move(factors);
}

std::shared_ptr<InterfaceAnalysisStore> make_interface_analysis_store() {
  return std::make_shared<InterfaceAnalysisStore>();
}

struct InterfaceSolve::Impl {
  int d = 0, w = 0, p = 0;
  Eigen::Index m = 0, mI = 0, mG = 0;  // poses: all, interior, interface
  std::vector<Eigen::Index> slot;      // local pose -> position in the factor's order
  std::vector<PosePair> pairs;         // Q_BB's pose blocks with slot[i] >= slot[j]
  std::vector<PosePair> cut;           // Q's cut blocks (i own, j neighbour), own id < other id
  std::vector<std::size_t> owned, neighbors;
  TeamInterface team;  // the team's interface in Sigma, in tangent coordinates
  Eigen::Index own_offset = 0;
  int id = 0;
  // The factors (InterfaceFactors), from the store where there is one, and the analyses they had
  // run before; L's trailing interface block at the current point and at a trial point.
  std::shared_ptr<InterfaceAnalysisStore> store;
  std::unique_ptr<InterfaceFactors> f;
  int analyses_before = 0;
  bool block_checked = false;  // A_bb's positions compared with f->block_pattern's
  Eigen::MatrixXd Lgg, pending_Lgg;
  bool sigma_ok = false;
  bool sigma_here = false;  // sigma_ok from this agent's own factor (not adopt_remote_sigma())
  bool grounded = false;    // the team's first interface pose held fixed (its p coordinates)
  double shift = 0.0;
  int pattern = -1;  // the Sigma factor last factored: 1 grounded, 0 not, -1 none
  std::vector<double> block_values;
  mutable Eigen::VectorXd b;  // scratch: J^T v in the block's own order
};

InterfaceSolve::InterfaceSolve(const BlockProblem& problem, const BlockLayout& layout, int id,
                               std::shared_ptr<InterfaceAnalysisStore> store)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.store = std::move(store);
  s.f = s.store ? s.store->take(id) : std::make_unique<InterfaceFactors>();
  // The trial points' factor takes the block factor's analysis when first needed (a copy, where
  // one held from another refinement may be of another pattern).
  s.f->pending.reset();
  s.analyses_before = s.f->analyses();
  s.d = problem.dim();
  s.w = s.d + 1;
  if (s.d != 2 && s.d != 3) throw std::invalid_argument("InterfaceSolve: d must be 2 or 3");
  s.p = s.d * (s.d + 1) / 2;
  s.id = id;
  s.owned = problem.owned();
  s.neighbors = problem.neighbors();
  s.m = static_cast<Eigen::Index>(s.owned.size());
  const Eigen::Index w = s.w;

  s.team = team_interface(layout, s.p);
  s.own_offset = s.team.block_offset[static_cast<std::size_t>(id)];
  OwnInterfaceLast own = own_interface_last(s.owned, layout, id, "InterfaceSolve");
  s.slot = std::move(own.slot);
  s.mI = own.interior;
  s.mG = s.m - s.mI;

  // Q_BB's pose blocks.
  const SparseMatrix& Q = problem.data_matrix();
  std::vector<std::vector<std::size_t>> column(static_cast<std::size_t>(s.m));  // into all
  std::vector<PosePair> all;
  for (Eigen::Index c = 0; c < Q.outerSize(); ++c) {
    const Eigen::Index j = c / w, u = c % w;
    for (SparseMatrix::InnerIterator it(Q, c); it; ++it) {
      const Eigen::Index i = it.row() / w, t = it.row() % w;
      auto& col = column[static_cast<std::size_t>(j)];
      std::size_t k = 0;
      while (k < col.size() && all[col[k]].i != i) ++k;
      if (k == col.size()) {
        col.push_back(all.size());
        all.push_back(PosePair{i, j, {}});
      }
      all[col[k]].q[static_cast<std::size_t>(u * w + t)] = it.value();
    }
  }
  // Interior poses first (fill-reducing order), the interface's last.
  place_interior_first(s.slot, [&](const auto& add) {
    for (const PosePair& pp : all) add(pp.i, pp.j);
  });
  for (PosePair& pp : all)
    if (s.slot[static_cast<std::size_t>(pp.i)] >= s.slot[static_cast<std::size_t>(pp.j)])
      s.pairs.push_back(std::move(pp));

  // The cut's blocks: Q(i, j) for own i and neighbour j is Q_NB's (j, i) block transposed.
  const SparseMatrix& Qnb = problem.neighbor_matrix();
  std::vector<std::vector<std::size_t>> cut_of(static_cast<std::size_t>(s.m));
  for (Eigen::Index c = 0; c < Qnb.outerSize(); ++c) {
    const Eigen::Index i = c / w, t = c % w;
    for (SparseMatrix::InnerIterator it(Qnb, c); it; ++it) {
      const Eigen::Index j = it.row() / w, u = it.row() % w;
      if (s.owned[static_cast<std::size_t>(i)] > s.neighbors[static_cast<std::size_t>(j)]) continue;
      auto& col = cut_of[static_cast<std::size_t>(i)];
      std::size_t k = 0;
      while (k < col.size() && s.cut[col[k]].j != j) ++k;
      if (k == col.size()) {
        col.push_back(s.cut.size());
        s.cut.push_back(PosePair{i, j, {}});
      }
      s.cut[col[k]].q[static_cast<std::size_t>(u * w + t)] = it.value();
    }
  }
}

InterfaceSolve::~InterfaceSolve() {
  Impl& s = *impl_;
  if (s.store && s.f) s.store->give(s.id, std::move(s.f));
}

int InterfaceSolve::analyses() const {
  return impl_->f->analyses() - impl_->analyses_before;
}

Eigen::Index InterfaceSolve::team_size() const {
  return impl_->team.size;
}
Eigen::Index InterfaceSolve::offset() const {
  return impl_->own_offset;
}
Eigen::Index InterfaceSolve::size() const {
  return impl_->p * impl_->mG;
}
Eigen::Index InterfaceSolve::block_offset(int b) const {
  return impl_->team.block_offset.at(static_cast<std::size_t>(b));
}
Eigen::Index InterfaceSolve::block_size(int b) const {
  return impl_->team.block_size.at(static_cast<std::size_t>(b));
}
double InterfaceSolve::shift() const {
  return impl_->shift;
}

namespace {

template <int D>
void block_into(const double* q, const Eigen::MatrixXd& Gi, const Eigen::MatrixXd& Gj, double* out,
                bool diagonal) {
  constexpr int P = D * (D + 1) / 2;
  double top = 0.0;
  tangent_block_fixed<D>(q, Gi, Gj, out, P, diagonal ? &top : nullptr);
}

}  // namespace

std::vector<double> InterfaceSolve::factor(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                           const Eigen::MatrixXd& egrad) {
  impl_->sigma_ok = false;
  return factor_impl(X, Xn, egrad, true, false);
}

std::vector<double> InterfaceSolve::factor_pending(const Eigen::MatrixXd& X,
                                                   const Eigen::MatrixXd& Xn,
                                                   const Eigen::MatrixXd& egrad) {
  InterfaceFactors& f = *impl_->f;
  if (!f.pending) {
    // The current factor's analysis (the pattern is the same at every point): a numeric
    // factorization only, as at the current point.
    f.pending = std::make_unique<SupernodalFactor>(SupernodalFactor::Ordering::kGiven);
    f.pending->adopt_analysis(*f.block);
  }
  return factor_impl(X, Xn, egrad, true, true);
}

void InterfaceSolve::commit_pending() {
  Impl& s = *impl_;
  if (!s.f->pending) throw std::logic_error("InterfaceSolve::commit_pending: no pending factor");
  std::swap(s.f->block, s.f->pending);
  std::swap(s.Lgg, s.pending_Lgg);
  s.sigma_ok = false;
}

std::vector<double> InterfaceSolve::factor_impl(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                                const Eigen::MatrixXd& egrad, bool multipliers,
                                                bool pending) {
  Impl& s = *impl_;
  const int d = s.d, w = s.w, p = s.p;
  if (X.rows() != d || X.cols() != w * s.m || egrad.rows() != d || egrad.cols() != X.cols() ||
      Xn.rows() != d)
    throw std::invalid_argument("InterfaceSolve::factor: not a rank-d point of the block");
  SupernodalFactor& block = pending ? *s.f->pending : *s.f->block;
  Eigen::MatrixXd& Lgg = pending ? s.pending_Lgg : s.Lgg;
  const auto skew = skew_pairs(d);
  std::vector<Eigen::MatrixXd> G(static_cast<std::size_t>(s.m));
  for (Eigen::Index i = 0; i < s.m; ++i)
    G[static_cast<std::size_t>(i)] = pose_basis(X.block(0, i * w, d, d), skew);
  const Eigen::Index n = s.m * p;
  // A's positions are the same at every point: compared with the held layout at the first one
  // (a store's factors may hold another block's), then only the values are written.
  const bool layout = !s.block_checked;
  TripletScatter& block_pattern = s.f->block_pattern;
  std::vector<int> rows, cols;
  std::vector<double>& vals = s.block_values;
  vals.clear();
  vals.reserve(s.pairs.size() * static_cast<std::size_t>(p * p));
  Eigen::MatrixXd B(p, p), Qm(w, w);
  for (const PosePair& pp : s.pairs) {
    const bool diag = pp.i == pp.j;
    const double* q = pp.q.data();
    if (diag && multipliers) {
      // H's multiplier term on the rotation part of the diagonal blocks (Q - Lambda, as
      // TangentPreconditioner::factorize(X, egrad)).
      Qm = Eigen::Map<const Eigen::MatrixXd>(q, w, w);
      const Eigen::MatrixXd YG =
          X.block(0, pp.j * w, d, d).transpose() * egrad.block(0, pp.j * w, d, d);
      Qm.topLeftCorner(d, d) -= 0.25 * (YG + YG.transpose());
      q = Qm.data();
    }
    if (d == 2)
      block_into<2>(q, G[static_cast<std::size_t>(pp.i)], G[static_cast<std::size_t>(pp.j)],
                    B.data(), diag);
    else
      block_into<3>(q, G[static_cast<std::size_t>(pp.i)], G[static_cast<std::size_t>(pp.j)],
                    B.data(), diag);
    const Eigen::Index ri = s.slot[static_cast<std::size_t>(pp.i)] * p;
    const Eigen::Index cj = s.slot[static_cast<std::size_t>(pp.j)] * p;
    for (int c = 0; c < p; ++c)
      for (int a = diag ? c : 0; a < p; ++a) {
        vals.push_back(B(a, c));
        if (layout) {
          rows.push_back(static_cast<int>(ri + a));
          cols.push_back(static_cast<int>(cj + c));
        }
      }
  }
  if (layout && !block_pattern.matches(n, rows, cols)) {
    // The pose pairs are distinct, so no position repeats.
    if (!block_pattern.build(n, rows, cols))
      throw std::logic_error("InterfaceSolve: a repeated entry in the block's Hessian");
  }
  s.block_checked = true;
  block_pattern.fill(vals);
  const bool ok = n > 0 && block.factor(block_pattern.matrix());
  // Far from a minimiser the block's Hessian may be indefinite: then its block without the
  // multiplier term (positive definite, as block Jacobi's), and Sigma is the Schur complement
  // of that modified H, still a symmetric positive definite preconditioner.
  if (!ok && multipliers) return factor_impl(X, Xn, egrad, false, pending);
  if (!ok) return {0.0};
  const Eigen::Index nI = s.mI * p, nG = s.mG * p;
  // L's interface block; the interface's Schur complement is L_GG L_GG^T.
  Lgg = block.trailing_block(nI);
  const Eigen::MatrixXd schur = Lgg.triangularView<Eigen::Lower>() * Lgg.transpose();

  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(2 + nG * (nG + 1) / 2) +
              s.cut.size() * static_cast<std::size_t>(2 + p * p));
  out.push_back(multipliers ? 1.0 : 2.0);
  for (Eigen::Index j = 0; j < nG; ++j)
    for (Eigen::Index i = j; i < nG; ++i) out.push_back(0.5 * (schur(i, j) + schur(j, i)));
  out.push_back(static_cast<double>(s.cut.size()));
  for (const PosePair& pp : s.cut) {
    const Eigen::MatrixXd Gj = pose_basis(Xn.block(0, pp.j * w, d, d), skew);
    if (d == 2)
      block_into<2>(pp.q.data(), G[static_cast<std::size_t>(pp.i)], Gj, B.data(), false);
    else
      block_into<3>(pp.q.data(), G[static_cast<std::size_t>(pp.i)], Gj, B.data(), false);
    out.push_back(static_cast<double>(s.owned[static_cast<std::size_t>(pp.i)]));
    out.push_back(static_cast<double>(s.neighbors[static_cast<std::size_t>(pp.j)]));
    out.insert(out.end(), B.data(), B.data() + p * p);
  }
  return out;
}

bool InterfaceSolve::assemble(const std::vector<const std::vector<double>*>& blocks,
                              const std::vector<double>& relative_shifts) {
  Impl& s = *impl_;
  const int p = s.p;
  s.sigma_ok = false;
  s.shift = 0.0;
  if (blocks.size() != s.team.block_offset.size())
    throw std::runtime_error("newton refine: interface shares from the wrong number of agents");
  std::vector<Eigen::Triplet<double>> t;
  double top = 0.0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const std::vector<double>& v = *blocks[b];
    auto fail = [b] {
      throw std::runtime_error("newton refine: malformed interface share from agent " +
                               std::to_string(b));
    };
    std::size_t k = 0;
    if (!read_schur_triangle(v, s.team.block_offset[b], s.team.block_size[b], t, top, k, fail))
      return false;  // that block's Hessian is not positive definite
    const double count = v[k++];
    const std::size_t per = static_cast<std::size_t>(2 + p * p);
    if (!(count >= 0) || v.size() != k + static_cast<std::size_t>(count) * per) fail();
    for (std::size_t e = 0; e < static_cast<std::size_t>(count); ++e, k += per) {
      auto ri = s.team.first.find(static_cast<std::size_t>(v[k]));
      auto ci = s.team.first.find(static_cast<std::size_t>(v[k + 1]));
      if (ri == s.team.first.end() || ci == s.team.first.end()) fail();
      for (int c = 0; c < p; ++c)
        for (int a = 0; a < p; ++a) {
          // Zeros too: Sigma's pattern, and so its factor's analysis, stays that of the cut.
          const double x = v[k + 2 + static_cast<std::size_t>(c * p + a)];
          const Eigen::Index r = ri->second + a, cc = ci->second + c;
          t.emplace_back(std::max(r, cc), std::min(r, cc), x);
        }
    }
  }
  if (s.team.size == 0) return false;
  // Grounded: the team's first interface pose is held fixed, its rows and columns replaced by
  // top I (u there is then 0 to the bit from a zero rhat there). The gauge is Sigma's kernel on
  // a connected graph; shifted instead, H + eta P_Gamma left it at eigenvalues of eta times the
  // interface's share of a rigid motion, and the preconditioner multiplied the round-off
  // component of the residual along it by up to 1 / eta: ais2klinik's fourth Newton step was
  // a global rotation of 3.4 rad (99.99 % of the step), whose round-off inner product with the
  // gradient the model counted as a decrease of 4.8e-6 that f (exactly invariant) could not
  // give (2.7e-8). The shifts remain for a Sigma that is indefinite away from a minimiser.
  for (bool ground : {true, false}) {
    if (ground && (s.team.size <= p)) continue;
    std::vector<Eigen::Triplet<double>> g;
    if (ground) {
      g.reserve(t.size() + static_cast<std::size_t>(p));
      for (const auto& e : t)
        if (e.row() >= p && e.col() >= p) g.push_back(e);
      for (Eigen::Index k = 0; k < p; ++k) g.emplace_back(k, k, std::max(top, 1e-300));
    }
    // Sigma's positions are those of the last point's unless the shares' layout changed.
    const std::vector<Eigen::Triplet<double>>& e = ground ? g : t;
    TripletScatter& scatter = s.f->sigma_pattern[ground ? 1 : 0];
    SparseMatrix summed;  // where a position repeats (not from well-formed shares): summed
    if (!scatter.assign(s.team.size, e)) {
      summed.resize(s.team.size, s.team.size);
      summed.setFromTriplets(e.begin(), e.end());
    }
    const SparseMatrix& sigma = summed.rows() > 0 ? summed : scatter.matrix();
    for (double rel : relative_shifts) {
      const double eta = rel * std::max(top, 1e-300);
      s.pattern = ground ? 1 : 0;
      if (s.f->sigma[s.pattern].factor(sigma, eta)) {
        s.sigma_ok = true;
        s.sigma_here = true;
        s.grounded = ground;
        s.shift = rel;
        return true;
      }
    }
  }
  return false;
}

std::vector<double> InterfaceSolve::sigma_values() const {
  const Impl& s = *impl_;
  if (!s.sigma_ok) return {0.0};
  std::vector<double> v{1.0, s.grounded ? 1.0 : 0.0, s.shift};
  const std::vector<double> x = s.f->sigma[s.grounded ? 1 : 0].values();
  v.insert(v.end(), x.begin(), x.end());
  return v;
}

bool InterfaceSolve::import_sigma(const double* v, std::size_t count) {
  Impl& s = *impl_;
  if (count < 3 || v[0] != 1.0) return false;
  const bool ground = v[1] != 0.0;
  if (s.pattern != (ground ? 1 : 0) || !s.f->sigma[s.pattern].import_values(v + 3, count - 3))
    return false;
  s.sigma_ok = true;
  s.sigma_here = true;
  s.grounded = ground;
  s.shift = v[2];
  return true;
}

Eigen::Index InterfaceSolve::grounded_pose() const {
  const Impl& s = *impl_;
  if (!s.sigma_ok || !s.grounded || s.own_offset != 0 || s.mG == 0) return -1;
  for (Eigen::Index i = 0; i < s.m; ++i)
    if (s.slot[static_cast<std::size_t>(i)] == s.mI) return i;
  return -1;
}

void InterfaceSolve::forward(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v, Eigen::VectorXd& y,
                             bool pending) const {
  const Impl& s = *impl_;
  const int p = s.p;
  s.b.resize(s.m * p);
  if (s.d == 2)
    tangent_coordinates<2>(X.data(), v.data(), s.m, s.b.data());
  else
    tangent_coordinates<3>(X.data(), v.data(), s.m, s.b.data());
  y.resize(s.m * p);
  for (Eigen::Index i = 0; i < s.m; ++i)
    y.segment(s.slot[static_cast<std::size_t>(i)] * p, p) = s.b.segment(i * p, p);
  if (pending && !s.f->pending)
    throw std::logic_error("InterfaceSolve::forward: no pending factor");
  (pending ? s.f->pending : s.f->block)->solve_l(y);
}

void InterfaceSolve::add_interface(const Eigen::VectorXd& y, double* team, bool pending) const {
  const Impl& s = *impl_;
  const Eigen::Index nG = s.mG * s.p;
  if (nG == 0) return;
  Eigen::Map<Eigen::VectorXd>(team + s.own_offset, nG) +=
      (pending ? s.pending_Lgg : s.Lgg) * y.tail(nG);
}

void InterfaceSolve::adopt_remote_sigma(bool grounded) {
  Impl& s = *impl_;
  s.sigma_ok = true;
  s.sigma_here = false;
  s.grounded = grounded;
}

bool InterfaceSolve::grounded() const {
  return impl_->grounded;
}

Eigen::VectorXd InterfaceSolve::solve(const Eigen::VectorXd& rhat) const {
  const Impl& s = *impl_;
  if (!s.sigma_ok || !s.sigma_here)
    throw std::logic_error("InterfaceSolve::solve: no factor of Sigma");
  Eigen::VectorXd u;
  if (s.grounded) {
    Eigen::VectorXd r = rhat;
    r.head(s.p).setZero();
    s.f->sigma[1].solve(r, u);
  } else {
    s.f->sigma[0].solve(rhat, u);
  }
  return u;
}

Eigen::MatrixXd InterfaceSolve::back(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                     const Eigen::VectorXd& rhat) const {
  if (!impl_->sigma_ok) throw std::logic_error("InterfaceSolve::back: no factor of Sigma");
  const Eigen::VectorXd u = solve(rhat);
  return back_own(X, y, u.data() + impl_->own_offset);
}

Eigen::MatrixXd InterfaceSolve::back_own(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                         const double* u_own) const {
  const Impl& s = *impl_;
  if (!s.sigma_ok) throw std::logic_error("InterfaceSolve::back_own: no factor of Sigma");
  const int p = s.p;
  const Eigen::Index nI = s.mI * p, nG = s.mG * p;
  Eigen::VectorXd v(y.size());
  v.head(nI) = y.head(nI);
  if (nG > 0) v.tail(nG) = s.Lgg.transpose() * Eigen::Map<const Eigen::VectorXd>(u_own, nG);
  s.f->block->solve_lt(v);
  for (Eigen::Index i = 0; i < s.m; ++i)
    s.b.segment(i * p, p) = v.segment(s.slot[static_cast<std::size_t>(i)] * p, p);
  const Eigen::Index ground = grounded_pose();
  if (ground >= 0) s.b.segment(ground * p, p).setZero();  // x_G = u = 0 there, to the bit
  Eigen::MatrixXd Z(s.d, X.cols());
  if (s.d == 2)
    tangent_vector<2>(X.data(), s.b.data(), s.m, Z.data());
  else
    tangent_vector<3>(X.data(), s.b.data(), s.m, Z.data());
  return Z;
}

}  // namespace tessera
