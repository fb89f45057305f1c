#include "distributed/tangent_coarse_space.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <tessera/graph/connectivity.hpp>

namespace tessera {

namespace {

// M -= U U^T M in place, U's columns a group's rigid motions (generator j on every piece,
// normalized; `s` = 1 / pieces): the mean over the pieces of each generator's rows q = j mod g
// taken out of those rows (each mean is taken before its own rows change and no other rows).
template <typename Derived>
void remove_rigid_means(Eigen::MatrixBase<Derived>& M, int g, double s) {
  const Eigen::Index m = M.rows();
  for (int j = 0; j < g; ++j) {
    Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(M.cols());
    for (Eigen::Index q = j; q < m; q += g) mean += M.row(q);
    mean *= s;
    for (Eigen::Index q = j; q < m; q += g) M.row(q) -= mean;
  }
}

}  // namespace

TangentCoarseSpace::Poses TangentCoarseSpace::weights_of(const CoarseSpace* space,
                                                         const BlockLayout& layout,
                                                         const std::vector<std::size_t>& ids) {
  Poses p;
  p.start.reserve(ids.size() + 1);
  p.start.push_back(0);
  for (std::size_t id : ids) {
    if (space) {
      for (std::size_t q = space->weight_start[id]; q < space->weight_start[id + 1]; ++q)
        p.weights.push_back({space->weight_aggregate[q], space->weight[q]});
    } else {
      p.weights.push_back({layout.owner[id], 1.0});
    }
    p.start.push_back(p.weights.size());
  }
  return p;
}

TangentCoarseSpace::TangentCoarseSpace(const CoarseSpace* space, const BlockLayout& layout,
                                       const std::vector<std::size_t>& owned,
                                       const std::vector<std::size_t>& neighbours, int d, int k,
                                       int min_group_blocks)
    : d_(d),
      k_(k),
      g_(k * (k - 1) / 2 + k),
      pieces_(space ? space->num_aggregates : layout.num_blocks) {
  if (k < 1) throw std::invalid_argument("TangentCoarseSpace: no active rows");
  if (min_group_blocks < 2)
    throw std::invalid_argument("TangentCoarseSpace: min_group_blocks must be >= 2");
  for (int a = 0; a < k; ++a)
    for (int b = a + 1; b < k; ++b) rotation_pairs_.emplace_back(a, b);
  // Groups of linked pieces: the components of the block graph (every agent has the layout, so
  // every agent finds the same numbering).
  const std::vector<std::size_t> component = connected_components(layout.adjacent);
  std::vector<int> group_of_component(component.size(), -1);
  group_of_piece_.resize(static_cast<std::size_t>(pieces_));
  for (int alpha = 0; alpha < pieces_; ++alpha) {
    const int block = space ? space->aggregate_block[static_cast<std::size_t>(alpha)] : alpha;
    int& g = group_of_component[component[static_cast<std::size_t>(block)]];
    if (g < 0) g = groups_++;
    group_of_piece_[static_cast<std::size_t>(alpha)] = g;
  }
  own_poses_ = weights_of(space, layout, owned);
  neighbour_poses_ = weights_of(space, layout, neighbours);
  std::vector<char> own(static_cast<std::size_t>(pieces_), 0), any = own;
  for (const Weight& w : own_poses_.weights)
    own[static_cast<std::size_t>(w.piece)] = any[static_cast<std::size_t>(w.piece)] = 1;
  for (const Weight& w : neighbour_poses_.weights) any[static_cast<std::size_t>(w.piece)] = 1;
  // A group of one block (a robot that has met no other) is left out of touched() and own(): no
  // Hessian product assembles its columns of A. A piece alone in its group moves only by its
  // gauge (A^+ is zero on its unknowns); the pieces of the smoothed space inside one lone block
  // bend it, which block Jacobi's solve with the block's own factor already does.
  std::vector<int> members(static_cast<std::size_t>(groups_), 0);
  {
    std::vector<int> last_block(static_cast<std::size_t>(groups_), -1);
    for (int alpha = 0; alpha < pieces_; ++alpha) {
      const int block = space ? space->aggregate_block[static_cast<std::size_t>(alpha)] : alpha;
      const auto g = static_cast<std::size_t>(group_of_piece_[static_cast<std::size_t>(alpha)]);
      if (last_block[g] != block) ++members[g];  // aggregates are numbered by block
      last_block[g] = block;
    }
  }
  std::vector<std::vector<Eigen::Index>> unknowns(static_cast<std::size_t>(groups_));
  for (int alpha = 0; alpha < pieces_; ++alpha)
    for (int j = 0; j < g_; ++j)
      unknowns[static_cast<std::size_t>(group_of_piece_[static_cast<std::size_t>(alpha)])]
          .push_back(alpha * g_ + j);
  for (std::size_t g = 0; g < unknowns.size(); ++g)
    if (members[g] >= min_group_blocks) linked_group_unknowns_.push_back(std::move(unknowns[g]));
  linked_.assign(static_cast<std::size_t>(pieces_), 0);
  for (int a = 0; a < pieces_; ++a) {
    if (members[static_cast<std::size_t>(group_of_piece_[static_cast<std::size_t>(a)])] <
        min_group_blocks)
      continue;
    linked_[static_cast<std::size_t>(a)] = 1;
    for (int j = 0; j < g_; ++j) {
      if (own[static_cast<std::size_t>(a)]) own_.push_back(a * g_ + j);
      if (any[static_cast<std::size_t>(a)]) touched_.push_back(a * g_ + j);
    }
  }
  // project() and expand() visit only the own poses some linked piece weighs (none before the
  // robots meet): a lone piece's entries of Phi^T v meet only zeros of A^+.
  for (std::size_t slot = 0; slot + 1 < own_poses_.start.size(); ++slot)
    for (std::size_t q = own_poses_.start[slot]; q < own_poses_.start[slot + 1]; ++q)
      if (linked_[static_cast<std::size_t>(own_poses_.weights[q].piece)]) {
        linked_slots_.push_back(slot);
        break;
      }
}

void TangentCoarseSpace::add_generator(int j, double x, double* e) const {
  const int rotations = static_cast<int>(rotation_pairs_.size());
  if (j < rotations) {
    const auto [a, b] = rotation_pairs_[static_cast<std::size_t>(j)];
    e[a + b * k_] += x;
    e[b + a * k_] -= x;
  } else {
    e[(j - rotations) + k_ * k_] += x;
  }
}

void TangentCoarseSpace::move(const double* e, const Eigen::MatrixXd& X, Eigen::Index s,
                              Eigen::MatrixXd& v) const {
  // A k x k times k x (d+1) product written out: Eigen's GEMM path costs more than the flops and
  // its coefficient-wise lazy product is a call per entry (both ran in every CG iteration). The
  // sums run in the same order as the lazy product's.
  const Eigen::Index k = k_, c = s * (d_ + 1);
  const double* x = X.data() + c * k;
  double* o = v.data() + c * k;
  for (Eigen::Index col = 0; col <= d_; ++col, x += k, o += k)
    for (Eigen::Index i = 0; i < k; ++i) {
      double acc = e[i] * x[0];
      for (Eigen::Index m = 1; m < k; ++m) acc += e[i + m * k] * x[m];
      o[i] += acc;
    }
  o -= k;  // the translation column
  for (Eigen::Index i = 0; i < k; ++i) o[i] += e[i + k * k];
}

template <class Slots>
void TangentCoarseSpace::project_over(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v,
                                      const Slots& slots, double* out) const {
  // Per piece, sum_i w_i [v_i X_i^T, v_i's translation] (k x (k+1)); <E, that> for each
  // generator E is its coordinate.
  const Eigen::Index kk = k_ * (k_ + 1);
  std::vector<double> acc(static_cast<std::size_t>(pieces_ * kk), 0.0);
  Eigen::MatrixXd N(k_, k_ + 1);
  const Eigen::Index k = k_;
  for (const auto slot : slots) {
    const auto s = static_cast<std::size_t>(slot);
    const Eigen::Index c = static_cast<Eigen::Index>(s) * (d_ + 1);
    // N = [v_s X_s^T, v_s's translation], the product written out as in move().
    const double* vs = v.data() + c * k;
    const double* xs = X.data() + c * k;
    for (Eigen::Index j = 0; j < k; ++j)
      for (Eigen::Index i = 0; i < k; ++i) {
        double acc = vs[i] * xs[j];
        for (Eigen::Index col = 1; col <= d_; ++col) acc += vs[i + col * k] * xs[j + col * k];
        N(i, j) = acc;
      }
    N.col(k_) = v.col(c + d_);
    for (std::size_t q = own_poses_.start[s]; q < own_poses_.start[s + 1]; ++q) {
      const Weight& w = own_poses_.weights[q];
      if (linked_[static_cast<std::size_t>(w.piece)])
        Eigen::Map<Eigen::MatrixXd>(acc.data() + w.piece * kk, k_, k_ + 1) += w.w * N;
    }
  }
  const int rotations = static_cast<int>(rotation_pairs_.size());
  for (int alpha = 0; alpha < pieces_; ++alpha) {
    const Eigen::Map<const Eigen::MatrixXd> A(acc.data() + alpha * kk, k_, k_ + 1);
    double* o = out + alpha * g_;
    for (int j = 0; j < rotations; ++j) {
      const auto [a, b] = rotation_pairs_[static_cast<std::size_t>(j)];
      o[j] += A(a, b) - A(b, a);
    }
    for (int a = 0; a < k_; ++a) o[rotations + a] += A(a, k_);
  }
}

void TangentCoarseSpace::project(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v,
                                 double* out) const {
  project_over(X, v, linked_slots_, out);
}

void TangentCoarseSpace::project(const Eigen::MatrixXd& X, const Eigen::MatrixXd& v,
                                 const std::vector<Eigen::Index>& slots, double* out) const {
  project_over(X, v, slots, out);
}

std::vector<Eigen::Index> TangentCoarseSpace::slots_of(const Poses& p, int piece) {
  std::vector<Eigen::Index> out;
  for (std::size_t s = 0; s + 1 < p.start.size(); ++s)
    for (std::size_t q = p.start[s]; q < p.start[s + 1]; ++q)
      if (p.weights[q].piece == piece) {
        out.push_back(static_cast<Eigen::Index>(s));
        break;
      }
  return out;
}

void TangentCoarseSpace::expand(const Eigen::MatrixXd& X, const Eigen::VectorXd& xi,
                                Eigen::MatrixXd& v) const {
  // Each own piece's [Omega c] (k x (k+1), column-major, one buffer: this runs twice in every CG
  // iteration), then each slot's blend of them; the sums in the order of add_generator() and of
  // Eigen's E_i += w E_alpha.
  const int k = k_;
  const std::size_t kk = static_cast<std::size_t>(k * (k + 1));
  std::vector<double> E(static_cast<std::size_t>(pieces_) * kk, 0.0);
  std::vector<char> has(static_cast<std::size_t>(pieces_), 0);  // empty: alone in its group
  for (int u : own_) {
    const auto piece = static_cast<std::size_t>(u / g_);
    has[piece] = 1;
    add_generator(u % g_, xi(u), E.data() + piece * kk);
  }
  std::vector<double> Ei(kk);
  for (std::size_t s : linked_slots_) {
    std::fill(Ei.begin(), Ei.end(), 0.0);
    for (std::size_t q = own_poses_.start[s]; q < own_poses_.start[s + 1]; ++q) {
      const Weight& w = own_poses_.weights[q];
      const auto piece = static_cast<std::size_t>(w.piece);
      if (!has[piece]) continue;
      const double* e = E.data() + piece * kk;
      for (std::size_t t = 0; t < kk; ++t) Ei[t] += w.w * e[t];
    }
    move(Ei.data(), X, static_cast<Eigen::Index>(s), v);
  }
}

void TangentCoarseSpace::unit(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn, int unknown,
                              Eigen::MatrixXd& v, Eigen::MatrixXd& vn) const {
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(k_, k_ + 1);
  add_generator(unknown % g_, 1.0, E.data());
  const int piece = unknown / g_;
  auto fill = [&](const Poses& p, const Eigen::MatrixXd& P, Eigen::MatrixXd& out) {
    out.setZero(P.rows(), P.cols());
    const std::size_t n = p.start.size() - 1;
    for (std::size_t s = 0; s < n; ++s)
      for (std::size_t q = p.start[s]; q < p.start[s + 1]; ++q)
        if (p.weights[q].piece == piece) {
          const Eigen::MatrixXd wE = p.weights[q].w * E;
          move(wE.data(), P, static_cast<Eigen::Index>(s), out);
        }
  };
  fill(own_poses_, X, v);
  fill(neighbour_poses_, Xn, vn);
}

void TangentCoarseSpace::lift_on(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn, int piece,
                                 const std::vector<Eigen::Index>& own,
                                 const std::vector<Eigen::Index>& neighbour, Eigen::MatrixXd& W,
                                 Eigen::MatrixXd& Wn) const {
  auto fill = [&](const Poses& p, const std::vector<Eigen::Index>& slots, const Eigen::MatrixXd& P,
                  Eigen::MatrixXd& out) {
    for (Eigen::Index s : slots)
      for (std::size_t q = p.start[static_cast<std::size_t>(s)];
           q < p.start[static_cast<std::size_t>(s) + 1]; ++q)
        if (p.weights[q].piece == piece) {
          const double w = p.weights[q].w;
          const Eigen::Index c = s * (d_ + 1);
          out.block(0, c, k_, d_ + 1) += w * P.middleCols(c, d_ + 1);
          out(k_, c + d_) += w;
        }
  };
  fill(own_poses_, own, X, W);
  fill(neighbour_poses_, neighbour, Xn, Wn);
}

void TangentCoarseSpace::apply_generator(int j, const Eigen::MatrixXd& M,
                                         Eigen::MatrixXd& out) const {
  out.setZero(k_, M.cols());
  const int rotations = static_cast<int>(rotation_pairs_.size());
  if (j < rotations) {  // Omega = e_a e_b^T - e_b e_a^T
    const auto [a, b] = rotation_pairs_[static_cast<std::size_t>(j)];
    out.row(a) = M.row(b);
    out.row(b) = -M.row(a);
  } else {  // c = e_a
    out.row(j - rotations) = M.row(k_);
  }
}

Eigen::MatrixXd TangentCoarseSpace::group_inverse(const Eigen::MatrixXd& Ag, double tol) const {
  const Eigen::Index m = Ag.rows();
  // P = I - U U^T, U's columns the group's rigid motions (generator j on every piece of the
  // group) normalized.
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(m, g_);
  const double s = 1.0 / std::sqrt(static_cast<double>(m / g_));
  for (Eigen::Index q = 0; q < m; ++q) U(q, q % g_) = s;
  const Eigen::MatrixXd PA = Ag - U * (U.transpose() * Ag);
  Eigen::MatrixXd B = PA - (PA * U) * U.transpose();
  B = (0.5 * (B + B.transpose())).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(B);
  const Eigen::VectorXd& l = eig.eigenvalues();
  const double top = l.size() > 0 ? l(l.size() - 1) : 0.0;
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(l.size());
  for (Eigen::Index i = 0; i < l.size(); ++i)
    if (top > 0 && l(i) > tol * top) inv(i) = 1.0 / l(i);
  const Eigen::MatrixXd& V = eig.eigenvectors();
  return V * inv.asDiagonal() * V.transpose();
}

Eigen::MatrixXd TangentCoarseSpace::pseudo_inverse(const Eigen::MatrixXd& A, double tol) const {
  const Eigen::Index n = size();
  if (A.rows() != n || A.cols() != n)
    throw std::invalid_argument("TangentCoarseSpace: coarse matrix of the wrong size");
  // Pieces of different groups share no measurement, so A is block diagonal over the groups and
  // so is its pseudo-inverse: one small eigendecomposition per group of two blocks or more (a
  // lone piece's block is all gauge, zero), not one of all the pieces' unknowns at every point.
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  for (const std::vector<Eigen::Index>& idx : linked_group_unknowns_)
    out(idx, idx) = group_inverse(A(idx, idx), tol);
  return out;
}

std::size_t TangentCoarseSpace::packed_size() const {
  std::size_t n = 0;
  for (const std::vector<Eigen::Index>& idx : linked_group_unknowns_)
    n += idx.size() * (idx.size() + 1) / 2;
  return n;
}

void TangentCoarseSpace::pack(const Eigen::MatrixXd& L, std::vector<double>& out) const {
  for (const std::vector<Eigen::Index>& idx : linked_group_unknowns_)
    for (std::size_t j = 0; j < idx.size(); ++j)
      for (std::size_t i = 0; i <= j; ++i)
        out.push_back(0.5 * (L(idx[i], idx[j]) + L(idx[j], idx[i])));
}

void TangentCoarseSpace::set_matrix(const double* packed, double tol) {
  set_matrices(packed, nullptr, tol);
}

void TangentCoarseSpace::set_matrices(const double* inverted, const double* galerkin, double tol) {
  matrices_.clear();
  auto unpack = [](const double*& packed, Eigen::Index m) {
    Eigen::MatrixXd M(m, m);
    for (Eigen::Index j = 0; j < m; ++j)
      for (Eigen::Index i = 0; i <= j; ++i) M(i, j) = M(j, i) = *packed++;
    return M;
  };
  for (const std::vector<Eigen::Index>& idx : linked_group_unknowns_) {
    const auto m = static_cast<Eigen::Index>(idx.size());
    GroupMatrix gm;
    const Eigen::MatrixXd M = unpack(inverted, m);  // the matrix whose pseudo-inverse is kept
    gm.A = galerkin ? unpack(galerkin, m) : M;
    // B = P M P with P = I - U U^T (U: the group's rigid motions, generator j on every piece,
    // normalized); U U^T's entries are 1/pieces where the generators agree.
    const double s = 1.0 / static_cast<double>(m / g_);
    Eigen::MatrixXd B = M;
    remove_rigid_means(B, g_, s);
    B.transposeInPlace();
    remove_rigid_means(B, g_, s);
    B = (0.5 * (B + B.transpose())).eval();
    const double c = B.diagonal().maxCoeff();
    for (Eigen::Index p = 0; p < m; ++p)
      for (Eigen::Index q = p % g_; q < m; q += g_) B(p, q) += c * s;
    gm.llt.compute(B);
    bool ok = c > 0 && gm.llt.info() == Eigen::Success;
    if (ok) {
      const Eigen::VectorXd pivots = gm.llt.matrixLLT().diagonal().cwiseAbs2();
      ok = pivots.minCoeff() > tol * pivots.maxCoeff();
    }
    if (ok) {
      // The pivots bound the smallest eigenvalue from above only: a group whose smallest was
      // 1.9e-11 of the largest passed them (city10000 online, far from the optimum), and its
      // inverse made the CG's steps long along a direction that is short in the preconditioner's
      // norm the trust region bounds (trials raising f by 5.8e6 inside a radius of 1.1). So
      // estimate it by inverse iteration with the factor: |B^-1 x| <= |x| / lambda_min and
      // c <= lambda_max, so the check never sends to the eigendecomposition a group whose
      // pseudo-inverse keeps every direction. The start is a fixed sequence: same bits everywhere.
      std::minstd_rand sequence(1);
      Eigen::VectorXd x(m);
      for (Eigen::Index i = 0; i < m; ++i)
        x(i) = static_cast<double>(sequence()) / static_cast<double>(std::minstd_rand::max()) - 0.5;
      double growth = 0.0;  // |B^-1 x| / |x| at the last iteration
      for (int k = 0; k < 8; ++k) {
        x /= x.norm();
        x = gm.llt.solve(x);
        growth = x.norm();
      }
      ok = growth * tol * c < 1.0;
    }
    if (!ok) {
      gm.dense = true;
      gm.inverse = group_inverse(M, tol);
    }
    matrices_.push_back(std::move(gm));
  }
}

Eigen::VectorXd TangentCoarseSpace::times_matrix(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(x.size());
  for (std::size_t g = 0; g < matrices_.size(); ++g)
    y(linked_group_unknowns_[g]) = matrices_[g].A * x(linked_group_unknowns_[g]);
  return y;
}

Eigen::VectorXd TangentCoarseSpace::times_inverse(const Eigen::VectorXd& x) const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(x.size());
  for (std::size_t g = 0; g < matrices_.size(); ++g) {
    const std::vector<Eigen::Index>& idx = linked_group_unknowns_[g];
    const GroupMatrix& gm = matrices_[g];
    if (gm.dense) {
      y(idx) = gm.inverse * x(idx);
      continue;
    }
    const double s = 1.0 / static_cast<double>(static_cast<Eigen::Index>(idx.size()) / g_);
    Eigen::VectorXd v = x(idx);
    remove_rigid_means(v, g_, s);
    v = gm.llt.solve(v);
    remove_rigid_means(v, g_, s);
    y(idx) = v;
  }
  return y;
}

}  // namespace tessera
