#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/pose_kernels.hpp>
#include <type_traits>
#include <utility>

#include "manifold/pose_lanes.hpp"
#include "problem/edge_lanes.hpp"
#include "util/double_pair.hpp"

namespace tessera {
namespace {

// One measurement as the cost loops read it (edge_term): R column-major, t, kappa, tau.
void pack_measurement(const Measurement& me, int d, double* out) {
  if (me.R.rows() != d || me.R.cols() != d || me.t.size() != d)
    throw std::invalid_argument("BlockProblem: measurement of the wrong dimension");
  for (int b = 0; b < d; ++b)
    for (int c = 0; c < d; ++c) out[b * d + c] = me.R(c, b);
  for (int c = 0; c < d; ++c) out[d * d + c] = me.t(c);
  out[d * d + d] = me.kappa;
  out[d * d + d + 1] = me.tau;
}

}  // namespace

BlockProblem::BlockProblem(int d, std::vector<std::size_t> owned,
                           const std::vector<Measurement>& measurements)
    : d_(d), owned_(std::move(owned)) {
  if (d_ != 2 && d_ != 3) throw std::invalid_argument("BlockProblem: d must be 2 or 3");
  // Slot of every pose id (a flat table: every agent scans all measurements it is given, and
  // a hash lookup per endpoint was most of that scan at 10^6 poses).
  std::size_t max_id = 0;
  for (std::size_t id : owned_) max_id = std::max(max_id, id);
  for (const auto& m : measurements) max_id = std::max({max_id, m.i, m.j});
  constexpr std::size_t kNotOwned = static_cast<std::size_t>(-1);
  std::vector<std::size_t> slot(owned_.empty() && measurements.empty() ? 0 : max_id + 1, kNotOwned);
  for (std::size_t s = 0; s < owned_.size(); ++s) {
    if (slot[owned_[s]] != kNotOwned)
      throw std::invalid_argument("BlockProblem: pose listed twice in block");
    slot[owned_[s]] = s;
  }
  // First pass: which measurements touch the block, and which neighbours they bring.
  std::vector<std::size_t> touching;
  for (std::size_t k = 0; k < measurements.size(); ++k) {
    const auto& m = measurements[k];
    const bool oi = slot[m.i] != kNotOwned, oj = slot[m.j] != kNotOwned;
    if (!oi && !oj) continue;
    touching.push_back(k);
    if (!oi) neighbors_.push_back(m.i);
    if (!oj) neighbors_.push_back(m.j);
  }
  std::sort(neighbors_.begin(), neighbors_.end());
  neighbors_.erase(std::unique(neighbors_.begin(), neighbors_.end()), neighbors_.end());
  for (std::size_t k = 0; k < neighbors_.size(); ++k) slot[neighbors_[k]] = owned_.size() + k;
  // The only copy of the measurements kept is packed_ (the cost loops read it); the data
  // matrices are built from the caller's, which outlive this constructor.
  std::vector<const Measurement*> ptrs;
  std::vector<std::size_t> si, sj;
  ptrs.reserve(touching.size());
  si.reserve(touching.size());
  sj.reserve(touching.size());
  edges_.reserve(touching.size());
  for (auto k : touching) {
    const Measurement& m = measurements[k];
    ptrs.push_back(&m);
    si.push_back(slot[m.i]);
    sj.push_back(slot[m.j]);
    edges_.push_back({si.back(), sj.back()});
  }
  // The measurements packed contiguously for the cost loops (edge_term).
  const std::size_t stride = static_cast<std::size_t>(d_ * d_ + d_ + 2);
  packed_.resize(ptrs.size() * stride);
  for (std::size_t k = 0; k < ptrs.size(); ++k)
    pack_measurement(*ptrs[k], d_, packed_.data() + k * stride);
  DataMatrixBlocks Q =
      build_data_matrix_blocks(ptrs, si, sj, d_, owned_.size() + neighbors_.size(), owned_.size());
  Q_bb_ = std::move(Q.own);
  Q_nb_ = std::move(Q.neighbour);
}

BlockProblem BlockProblem::whole_graph(int d, std::size_t num_poses,
                                       const std::vector<Measurement>& measurements) {
  std::vector<std::size_t> all(num_poses);
  for (std::size_t i = 0; i < num_poses; ++i) all[i] = i;
  return BlockProblem(d, std::move(all), measurements);
}

void BlockProblem::extend(const std::vector<std::size_t>& new_owned,
                          const std::vector<Measurement>& measurements, std::size_t first_new) {
  if (first_new > measurements.size())
    throw std::invalid_argument("BlockProblem::extend: first_new beyond the measurements");
  if (owned_slot_.size() != owned_.size()) {
    owned_slot_.clear();
    owned_slot_.reserve(owned_.size() + new_owned.size());
    for (std::size_t s = 0; s < owned_.size(); ++s) owned_slot_.emplace(owned_[s], s);
  }
  for (std::size_t id : new_owned) {
    if (std::binary_search(neighbors_.begin(), neighbors_.end(), id))
      throw std::invalid_argument("BlockProblem::extend: pose " + std::to_string(id) +
                                  " is a neighbour, not a new pose");
    if (!owned_slot_.emplace(id, owned_.size()).second)
      throw std::invalid_argument("BlockProblem::extend: pose listed twice in block");
    owned_.push_back(id);
  }
  const std::size_t m_old = owned_.size() - new_owned.size(), m = owned_.size();
  const std::size_t k_old = neighbors_.size();
  auto owned = [&](std::size_t id) { return owned_slot_.count(id) != 0; };
  // The new measurements touching the block and the neighbours they bring.
  std::vector<std::size_t> touching, added;
  for (std::size_t k = first_new; k < measurements.size(); ++k) {
    const Measurement& me = measurements[k];
    const bool oi = owned(me.i), oj = owned(me.j);
    if (!oi && !oj) continue;
    // Checked before the block changes further (pack_measurement checks again, later).
    if (me.R.rows() != d_ || me.R.cols() != d_ || me.t.size() != d_)
      throw std::invalid_argument("BlockProblem: measurement of the wrong dimension");
    touching.push_back(k);
    for (std::size_t other : {oi ? std::size_t(-1) : me.i, oj ? std::size_t(-1) : me.j})
      if (other != std::size_t(-1) &&
          !std::binary_search(neighbors_.begin(), neighbors_.end(), other))
        added.push_back(other);
  }
  std::sort(added.begin(), added.end());
  added.erase(std::unique(added.begin(), added.end()), added.end());
  // Merged neighbour order; remap[k] = new index of old neighbour k (increasing, so the rows
  // of Q_NB keep their order inside every column).
  std::vector<std::size_t> merged(k_old + added.size()), remap(k_old);
  std::merge(neighbors_.begin(), neighbors_.end(), added.begin(), added.end(), merged.begin());
  for (std::size_t k = 0, at = 0; k < k_old; ++k) {
    while (merged[at] != neighbors_[k]) ++at;
    remap[k] = at;
  }
  neighbors_ = std::move(merged);
  auto neighbour_slot = [&](std::size_t id) {
    return m + static_cast<std::size_t>(std::lower_bound(neighbors_.begin(), neighbors_.end(), id) -
                                        neighbors_.begin());
  };
  for (Edge& e : edges_) {
    if (e.slot_i >= m_old) e.slot_i = m + remap[e.slot_i - m_old];
    if (e.slot_j >= m_old) e.slot_j = m + remap[e.slot_j - m_old];
  }
  std::vector<const Measurement*> ptrs;
  std::vector<std::size_t> si, sj;
  const std::size_t stride = static_cast<std::size_t>(d_ * d_ + d_ + 2);
  std::size_t at = packed_.size();
  packed_.resize(packed_.size() + touching.size() * stride);
  for (std::size_t k : touching) {
    const Measurement& me = measurements[k];
    ptrs.push_back(&me);
    si.push_back(owned(me.i) ? owned_slot_[me.i] : neighbour_slot(me.i));
    sj.push_back(owned(me.j) ? owned_slot_[me.j] : neighbour_slot(me.j));
    edges_.push_back({si.back(), sj.back()});
    pack_measurement(me, d_, packed_.data() + at);
    at += stride;
  }
  // The old matrices in the new slots (Q_NB's rows renumbered in place), plus the new terms.
  const Eigen::Index w = d_ + 1;
  Q_nb_.makeCompressed();
  for (Eigen::Index e = 0; e < Q_nb_.nonZeros(); ++e) {
    int& row = Q_nb_.innerIndexPtr()[e];
    row = static_cast<int>(w * static_cast<Eigen::Index>(remap[static_cast<std::size_t>(row / w)]) +
                           row % w);
  }
  const DataMatrixBlocks delta =
      build_data_matrix_blocks(ptrs, si, sj, d_, m + neighbors_.size(), m);
  Q_bb_.conservativeResize(w * static_cast<Eigen::Index>(m), w * static_cast<Eigen::Index>(m));
  Q_nb_.conservativeResize(w * static_cast<Eigen::Index>(neighbors_.size()),
                           w * static_cast<Eigen::Index>(m));
  if (delta.own.nonZeros() > 0) Q_bb_ = SparseMatrix(Q_bb_ + delta.own);
  if (delta.neighbour.nonZeros() > 0) Q_nb_ = SparseMatrix(Q_nb_ + delta.neighbour);
  Q_bb_.makeCompressed();
  Q_nb_.makeCompressed();
  if (Q_bb_blocks_) use_pose_blocks();
  X_n_.resize(0, 0);  // the neighbours' poses are stale: set_neighbor_poses again
  linear_.resize(0, 0);
}

void BlockProblem::use_pose_blocks() {
  Q_bb_blocks_.emplace(Q_bb_, d_ + 1);
}

void BlockProblem::times_own(const Eigen::MatrixXd& X, double scale, Eigen::MatrixXd& out) const {
  if (Q_bb_blocks_)
    Q_bb_blocks_->times(X, scale, out);
  else
    scaled_dense_times_sparse(X, Q_bb_, scale, out);
}

void BlockProblem::set_neighbor_poses(const Eigen::MatrixXd& X_neighbors) {
  if (X_neighbors.cols() != (d_ + 1) * static_cast<Eigen::Index>(neighbors_.size()))
    throw std::invalid_argument("BlockProblem: neighbour poses have the wrong size");
  X_n_ = X_neighbors;
  scaled_dense_times_sparse(X_n_, Q_nb_, 1.0, linear_);
}

double BlockProblem::cost(const Eigen::MatrixXd& X, double* share) const {
  // Summed edge by edge rather than as tr(X Q X^T): the trace form cancels large terms and
  // loses ~8 digits near the optimum, which would blind the trust-region ratio test.
  return edge_sum(X, share);
}

Eigen::MatrixXd BlockProblem::euclidean_gradient(const Eigen::MatrixXd& X) const {
  Eigen::MatrixXd G;
  times_own(X, 2.0, G);
  if (!neighbors_.empty()) G += 2.0 * linear_;
  return G;
}

Eigen::MatrixXd BlockProblem::euclidean_gradient(const Eigen::MatrixXd& X,
                                                 const Eigen::MatrixXd& X_neighbors) const {
  if (X_neighbors.cols() != (d_ + 1) * static_cast<Eigen::Index>(neighbors_.size()))
    throw std::invalid_argument("BlockProblem: neighbour poses have the wrong size");
  Eigen::MatrixXd G;
  times_own(X, 2.0, G);
  if (!neighbors_.empty()) {
    Eigen::MatrixXd linear;
    scaled_dense_times_sparse(X_neighbors, Q_nb_, 1.0, linear);
    G += 2.0 * linear;
  }
  return G;
}

Eigen::MatrixXd BlockProblem::riemannian_gradient(const Eigen::MatrixXd& X,
                                                  const Eigen::MatrixXd& egrad) const {
  return manifold(static_cast<int>(X.rows())).tangent_project(X, egrad);
}

Eigen::MatrixXd BlockProblem::riemannian_gradient(const Eigen::MatrixXd& X,
                                                  Eigen::MatrixXd&& egrad) const {
  return manifold(static_cast<int>(X.rows())).tangent_project(X, std::move(egrad));
}

Eigen::MatrixXd BlockProblem::hessian_vector(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad,
                                             const Eigen::MatrixXd& V) const {
  // Proj_X(2 V Q_BB) - Weingarten(X, egrad, V), fused (problem/pose_kernels.hpp).
  Eigen::MatrixXd H;
  times_own(V, 2.0, H);
  apply_hessian_projection(X, egrad, V, d_, H);
  return H;
}

namespace {

// edge_term<3, 3> (the 3D agents' active rows, most of their cost evaluations) with rows 0 and
// 1 of every difference in one register (GCC's vector extension: SSE2 on x86-64) and row 2
// apart. Each difference is formed element-wise as in edge_term's loop; the squares are then added
// to rot and tr one by one in the loop's order (row 0's, row 1's, row 2's), so the same value.
inline double edge_term_3x3(const double* Xi, const double* Xj, const double* m) {
  const double* Rm = m;
  const double* t = m + 9;
  const DoublePair xi0 = load_pair(Xi), xi1 = load_pair(Xi + 3), xi2 = load_pair(Xi + 6);
  DoublePair ta = load_pair(Xj + 9) - load_pair(Xi + 9);
  ta -= xi0 * t[0];
  ta -= xi1 * t[1];
  ta -= xi2 * t[2];
  const DoublePair ta2 = ta * ta;
  DoublePair v2[3];
#pragma GCC unroll 3
  for (int b = 0; b < 3; ++b) {
    DoublePair v = load_pair(Xj + 3 * b);
    v -= xi0 * Rm[3 * b];
    v -= xi1 * Rm[3 * b + 1];
    v -= xi2 * Rm[3 * b + 2];
    v2[b] = v * v;
  }
  double rot = 0.0, tr = 0.0;
#pragma GCC unroll 2
  for (int a = 0; a < 2; ++a) {
    tr += ta2[a];
    rot += v2[0][a];
    rot += v2[1][a];
    rot += v2[2][a];
  }
  double t2 = Xj[11] - Xi[11];
#pragma GCC unroll 3
  for (int c = 0; c < 3; ++c) t2 -= Xi[3 * c + 2] * t[c];
  tr += t2 * t2;
#pragma GCC unroll 3
  for (int b = 0; b < 3; ++b) {
    double v = Xj[3 * b + 2];
#pragma GCC unroll 3
    for (int c = 0; c < 3; ++c) v -= Xi[3 * c + 2] * Rm[3 * b + c];
    rot += v * v;
  }
  return m[12] * rot + m[13] * tr;
}

// One measurement's term, kappa ||X_j^R - X_i^R R||^2 + tau ||t_j - t_i - X_i^R t||^2, for a fixed
// d (and, when R > 0, a fixed number of rows): the same operations in the same order as the
// runtime-d loops it replaces (bit-identical), unrolled by the compiler. `m` is the edge's
// packed measurement: R (d x d, column-major), t (d), kappa, tau.
template <int D, int R>
double edge_term(const double* Xi, const double* Xj, const double* m, Eigen::Index r_runtime) {
  if constexpr (D == 3 && R == 3) return edge_term_3x3(Xi, Xj, m);
  const Eigen::Index r = R > 0 ? R : r_runtime;
  const double* Rm = m;
  const double* t = m + D * D;
  double rot = 0.0, tr = 0.0;
#pragma GCC unroll 16
  for (Eigen::Index a = 0; a < r; ++a) {
    double ta = Xj[D * r + a] - Xi[D * r + a];
#pragma GCC unroll 16
    for (int c = 0; c < D; ++c) ta -= Xi[c * r + a] * t[c];
    tr += ta * ta;
#pragma GCC unroll 16
    for (int b = 0; b < D; ++b) {
      double v = Xj[b * r + a];
#pragma GCC unroll 16
      for (int c = 0; c < D; ++c) v -= Xi[c * r + a] * Rm[b * D + c];
      rot += v * v;
    }
  }
  return m[D * D + D] * rot + m[D * D + D + 1] * tr;
}

}  // namespace

template <int D, int R>
double BlockProblem::sum_edges(const Eigen::MatrixXd& X, double* share) const {
  const Eigen::Index w = D + 1;
  const std::size_t m = owned_.size();
  const Eigen::Index r = X.rows();
  auto column = [&](std::size_t slot) -> const double* {
    return slot < m ? X.data() + r * w * static_cast<Eigen::Index>(slot)
                    : X_n_.data() + r * w * static_cast<Eigen::Index>(slot - m);
  };
  constexpr std::size_t stride = D * D + D + 2;
  const double* packed = packed_.data();
  double f = 0.0, s = 0.0;
  std::size_t k = 0;
  if constexpr (D == 3 && R == 3) {
    // pose_lanes() terms at a time, one a vector lane (the same bits as edge_term<3, 3>), added
    // up in order as below.
    static_assert(std::is_standard_layout_v<Edge> && sizeof(Edge) == 2 * sizeof(std::size_t),
                  "Edge is its two slots");
    k = sum_edge_terms_in_lanes(reinterpret_cast<const std::size_t*>(edges_.data()), edges_.size(),
                                X.data(), X_n_.data(), m, packed, f, s);
  }
  for (; k < edges_.size(); ++k) {
    const Edge& e = edges_[k];
    const double c = edge_term<D, R>(column(e.slot_i), column(e.slot_j), packed + k * stride, r);
    f += c;
    s += (e.slot_i < m && e.slot_j < m) ? c : 0.5 * c;
  }
  if (share) *share = s;
  return f;
}

double BlockProblem::edge_sum(const Eigen::MatrixXd& X, double* share) const {
  // The agents' active rows are d (lifted starts), the centralized solver's r = d + 1 or more.
  if (d_ == 2) return X.rows() == 2 ? sum_edges<2, 2>(X, share) : sum_edges<2, 0>(X, share);
  return X.rows() == 3 ? sum_edges<3, 3>(X, share) : sum_edges<3, 0>(X, share);
}

double BlockProblem::cost_share(const Eigen::MatrixXd& X) const {
  double share = 0.0;
  edge_sum(X, &share);
  return share;
}

}  // namespace tessera
