#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <tessera/distributed/agent_state.hpp>
#include <utility>

#include "distributed/nonzero_rows.hpp"
#include "distributed/pose_block_codec.hpp"
#include "util/frobenius_inner.hpp"

namespace tessera {

AgentState::AgentState(int id, int d, const BlockLayout& layout,
                       const std::vector<Measurement>& measurements, const Eigen::MatrixXd& Y0,
                       const BlockUpdateOptions& options)
    : id_(id),
      d_(d),
      layout_(layout),
      problem_(d, layout.poses[static_cast<std::size_t>(id)], measurements),
      coarse_(std::in_place, id, d, layout, problem_.owned(), problem_.neighbors(), measurements),
      max_factor_entries_(options.max_factor_entries) {
  problem_.use_pose_blocks();  // the rounds' gradients and Hessian products (~a fifth of them)
  const Eigen::Index cols = (d + 1) * static_cast<Eigen::Index>(problem_.num_owned());
  if (Y0.cols() != cols)
    throw std::invalid_argument("AgentState: initial block has the wrong size");
  Y = Y0;
  P = Y0;
  V = Y0;
  Y_prev = Y0;
  V_prev = Y0;
  Yn = Eigen::MatrixXd::Zero(Y0.rows(),
                             (d + 1) * static_cast<Eigen::Index>(problem_.num_neighbors()));
  Pn = Yn;
  Vn = Yn;
  Yn_prev = Yn;
  // The factors the updates will use are computed with the rest of the set-up, not in a round.
  // The Q_BB factor comes first: when it is too large (block-diagonal fallback, e.g. 20k-pose
  // 3D blocks), the tangent one (p x p pose blocks instead of (d+1) x (d+1): 2.25x the entries
  // in 3D, as many in 2D) is too large as well, and its analysis is skipped (a 100k-pose grid
  // with N = 5 spent 2 s more CPU in set-up analysing tangent factors it could not use).
  // Whether the Q_BB factor would be too large is known from its symbolic analysis alone.
  block_factor_too_large_ = BlockPreconditioner::falls_back(
      problem_, BlockPreconditioner::kDefaultRelativeShift, max_factor_entries_);
  if (options.precondition && options.tangent_preconditioner && !block_factor_too_large_) {
    const std::vector<Eigen::Index> rows = nonzero_rows(Y0, Eigen::MatrixXd());
    if (static_cast<int>(rows.size()) == d) build_tangent(Y0(rows, Eigen::all), options);
  }
  if (block_factor_too_large_) tangent_tried_ = true;  // never build it later either
  // With the tangent factor the rank-d updates do not read the Q_BB factor, so it is not
  // computed here: held beside the tangent one it was a third to a half of an agent's memory
  // in the rounds (a 16,000-pose 3D block: ~70 of ~200 MB of heap), and factoring it only to
  // drop it was 787 M of the 3.58 G instructions of the 5 agents' set-up on cubicle. Whatever
  // needs it later (an update above rank d, the greedy_newton score, a failed tangent
  // factorization) factors it then: the same factor, so the same iterates. Without a tangent
  // factor it is the updates' preconditioner, computed with the rest of the set-up as before.
  if (!(tangent_ && tangent_->factored())) euclidean();
}

const CoarseTerms& AgentState::coarse() const {
  if (!coarse_)
    coarse_.emplace(id_, d_, layout_, problem_.owned(), problem_.neighbors(), *coarse_source_);
  return *coarse_;
}

void AgentState::extend(const std::vector<Measurement>& measurements, std::size_t first_new,
                        const Eigen::MatrixXd& Y0, double refactor_growth) {
  const auto& own = layout_.poses[static_cast<std::size_t>(id_)];
  const auto& had = problem_.owned();
  if (own.size() < had.size() || !std::equal(had.begin(), had.end(), own.begin()))
    throw std::invalid_argument("AgentState::extend: the block lost or reordered poses");
  const Eigen::Index w = d_ + 1;
  if (Y0.cols() != w * static_cast<Eigen::Index>(own.size()))
    throw std::invalid_argument("AgentState::extend: block of the wrong size");
  const std::size_t m_old = had.size();
  problem_.extend(
      std::vector<std::size_t>(own.begin() + static_cast<std::ptrdiff_t>(m_old), own.end()),
      measurements, first_new);
  coarse_.reset();
  coarse_source_ = &measurements;
  smoothed_.reset();  // built for the old blocks
  space_.reset();
  Y = P = V = Y_prev = V_prev = Y0;
  Yn = Pn = Vn = Yn_prev =
      Eigen::MatrixXd::Zero(Y0.rows(), w * static_cast<Eigen::Index>(problem_.num_neighbors()));
  neighbours_set_.resize(0, 0);
  rows_.clear();
  updated_grad_norm_sq_ = -1.0;
  precon_.reset();
  if (tangent_ && tangent_->factored()) {
    // Poses outside the factor after this growth, against the poses it was computed for.
    const double unfactored = static_cast<double>(problem_.num_owned() - m_old) +
                              static_cast<double>(tangent_->grown_poses());
    const double factored =
        static_cast<double>(m_old) - static_cast<double>(tangent_->grown_poses());
    const std::vector<Eigen::Index> rows = nonzero_rows(Y0, Eigen::MatrixXd());
    const bool grown = unfactored <= refactor_growth * factored &&
                       static_cast<int>(rows.size()) == d_ &&
                       tangent_->grow(problem_, Y0(rows, Eigen::all));
    if (!grown) {
      tangent_.reset();
      tangent_tried_ = false;
    }
  } else if (!block_factor_too_large_) {
    tangent_.reset();
    tangent_tried_ = false;
  }
}

void AgentState::neighbours_moved(const std::vector<Measurement>& measurements) {
  coarse_.reset();
  coarse_source_ = &measurements;
  smoothed_.reset();
  space_.reset();
}

void AgentState::apply_coarse(const std::vector<Eigen::MatrixXd>& motions) {
  const Eigen::MatrixXd& own = motions[static_cast<std::size_t>(id_)];
  apply_motion(own, d_, Y);
  apply_motion(own, d_, V);
  const auto& nb = problem_.neighbors();
  for (std::size_t k = 0; k < nb.size(); ++k) {
    const Eigen::MatrixXd& z = motions[static_cast<std::size_t>(layout_.owner[nb[k]])];
    apply_motion(z, d_, Yn, static_cast<Eigen::Index>(k), 1);
    apply_motion(z, d_, Vn, static_cast<Eigen::Index>(k), 1);
  }
}

void AgentState::use_coarse_space(std::shared_ptr<const CoarseSpace> space,
                                  const std::vector<Measurement>& measurements) {
  smoothed_.reset();
  space_ = std::move(space);
  if (space_)
    smoothed_.emplace(*space_, id_, d_, problem_.owned(), problem_.neighbors(), measurements);
}

void AgentState::apply_smoothed_coarse(const std::vector<Eigen::MatrixXd>& motions) {
  apply_blended_motions(*space_, motions, d_, problem_.owned(), Y, V);
  apply_blended_motions(*space_, motions, d_, problem_.neighbors(), Yn, Vn);
}

BlockPreconditioner& AgentState::euclidean() {
  if (!precon_) {
    precon_ = std::make_unique<BlockPreconditioner>(
        problem_, BlockPreconditioner::kDefaultRelativeShift, max_factor_entries_);
    block_factor_too_large_ = precon_->block_diagonal();
  }
  return *precon_;
}

bool AgentState::build_tangent(const Eigen::MatrixXd& X, const BlockUpdateOptions& options) {
  if (tangent_tried_) return tangent_ && tangent_->usable();
  tangent_tried_ = true;
  // The Q_BB factor's cap bounds this one too (it may be set lower for a large team on one host,
  // runtime/team_memory.hpp); 0 there means no cap here either.
  // Supernodal factorization above options.tangent_supernodal_min_flops, solves simplicial.
  tangent_ = std::make_unique<TangentPreconditioner>(problem_, options.tangent_relative_shift,
                                                     max_factor_entries_,
                                                     options.tangent_supernodal_min_flops, true);
  tangent_->set_split_dots(options.tangent_split_dots);
  const bool factored = tangent_->usable() && tangent_->factorize(X);
  count_tangent_factorizations(0);
  if (!factored) tangent_.reset();
  return tangent_ != nullptr;
}

void AgentState::count_tangent_factorizations(int before) {
  if (!tangent_) return;
  const int done = tangent_->factorizations() - before;
  tangent_factorizations_total_ += done;
  tangent_factor_flops_total_ += done * tangent_->factor_flops();
}

PoseBlockMessage AgentState::publish(const Eigen::MatrixXd& X, BlockKind kind, int recipient,
                                     std::uint32_t round, std::uint32_t phase) const {
  const int k = layout_.adjacency_index(id_, recipient);
  if (k < 0) throw std::logic_error("AgentState::publish: recipient is not a neighbour block");
  return encode_public_poses(layout_, id_, static_cast<std::size_t>(k), d_, X, kind, round, phase);
}

void AgentState::absorb(const PoseBlockMessage& m, Eigen::MatrixXd& copy) const {
  decode_neighbour_poses(m, problem_.neighbors(), d_, id_, copy);
}

void AgentState::set_point(const Eigen::MatrixXd& X, const Eigen::MatrixXd& neighbours) {
  // Active rows: non-zero somewhere in the block or in the neighbours' poses.
  std::vector<Eigen::Index> rows = nonzero_rows(X, neighbours);
  if (rows.empty()) rows.push_back(0);  // all zero (not a manifold point): keep one row
  const bool same_rows = rows == rows_;
  rows_ = std::move(rows);
  if (problem_.num_neighbors() == 0) return;
  if (same_rows && neighbours_set_.size() == neighbours.size() && neighbours_set_ == neighbours)
    return;
  neighbours_set_ = neighbours;
  problem_.set_neighbor_poses(active_part(neighbours));
  ++neighbours_version_;
}

Eigen::MatrixXd AgentState::active_part(const Eigen::MatrixXd& X) const {
  const auto k = static_cast<Eigen::Index>(rows_.size());
  if (k == X.rows()) return X;
  if (k == 3 && rows_.back() == 2) {
    // A 3D lifted point's active rows are its first 3 (rows_ is increasing): copied column by
    // column, without an index per entry.
    Eigen::MatrixXd out(3, X.cols());
    const Eigen::Index r = X.rows();
    const double* x = X.data();
    double* o = out.data();
    for (Eigen::Index j = 0; j < X.cols(); ++j, x += r, o += 3) {
      o[0] = x[0];
      o[1] = x[1];
      o[2] = x[2];
    }
    return out;
  }
  return X(rows_, Eigen::all);
}

LocalStatus AgentState::status(bool newton_score) {
  set_point(Y, Yn);
  LocalStatus s;
  if (newton_score) {
    // The score needs the gradient itself, not only its norm: no reuse here.
    const Eigen::MatrixXd Ya = active_part(Y);
    s.cost_share = problem_.cost_share(Ya);
    const Eigen::MatrixXd g = problem_.riemannian_gradient(Ya, problem_.euclidean_gradient(Ya));
    s.grad_norm_sq = g.squaredNorm();
    const Eigen::MatrixXd z =
        euclidean().apply(problem_.manifold(static_cast<int>(Ya.rows())), Ya, g);
    s.block_grad_norm = std::sqrt(std::max(0.0, frobenius_inner(z, g)));
    return s;
  }
  if (updated_grad_norm_sq_ >= 0 && updated_version_ == neighbours_version_ && Y == updated_X_) {
    // Same point, same neighbours (and active rows): the update's gradient norm and cost share
    // are what this status would compute, bit for bit.
    s.cost_share = updated_cost_share_;
    s.grad_norm_sq = updated_grad_norm_sq_;
  } else {
    const Eigen::MatrixXd Ya = active_part(Y);
    s.cost_share = problem_.cost_share(Ya);
    s.grad_norm_sq =
        problem_.riemannian_gradient(Ya, problem_.euclidean_gradient(Ya)).squaredNorm();
  }
  s.block_grad_norm = std::sqrt(s.grad_norm_sq);
  return s;
}

Eigen::MatrixXd AgentState::update(const Eigen::MatrixXd& X0, const Eigen::MatrixXd& neighbours,
                                   const BlockUpdateOptions& options) {
  set_point(X0, neighbours);
  // The tangent factor needs rank-d points (docs/irbcd.md section 5): the active rows of a
  // lifted start. After a saddle escape (every row active), when its factor would be too large
  // or fails, the Q_BB factor is used.
  // Every row active (r = d, or after a saddle escape): work on X0 itself, no copy of it.
  const bool all_rows = static_cast<Eigen::Index>(rows_.size()) == X0.rows();
  const Eigen::MatrixXd active_copy = all_rows ? Eigen::MatrixXd() : active_part(X0);
  const Eigen::MatrixXd& Xa = all_rows ? X0 : active_copy;
  BlockPreconditioner* euclid = nullptr;
  const TangentPreconditioner* tangent = nullptr;
  if (options.precondition) {
    bool prepared = false;
    if (options.tangent_preconditioner && Xa.rows() == d_ && build_tangent(Xa, options)) {
      const int before = tangent_->factorizations();
      prepared = tangent_->prepare(Xa, options.tangent_refresh_interval);
      count_tangent_factorizations(before);
    }
    if (prepared)
      tangent = tangent_.get();
    else
      euclid = &euclidean();
  }
  BlockUpdateStats stats;
  Eigen::MatrixXd Xn =
      block_update(problem_, Xa, options, euclid, &updated_grad_norm_sq_, tangent, &stats);
  if (all_rows) {
    updated_X_ = std::move(Xn);
  } else if (rows_.back() == static_cast<Eigen::Index>(rows_.size()) - 1) {
    // The first k rows (a lifted point's): column by column, the rest +0 as Zero() gives, in
    // one pass instead of zeroing everything and scattering through a row index.
    const Eigen::Index k = Xn.rows(), r = X0.rows();
    updated_X_.resize(r, X0.cols());
    const double* x = Xn.data();
    double* o = updated_X_.data();
    for (Eigen::Index j = 0; j < X0.cols(); ++j, x += k, o += r) {
      for (Eigen::Index i = 0; i < k; ++i) o[i] = x[i];
      for (Eigen::Index i = k; i < r; ++i) o[i] = 0.0;
    }
  } else {
    updated_X_ = Eigen::MatrixXd::Zero(X0.rows(), X0.cols());
    updated_X_(rows_, Eigen::all) = Xn;
  }
  ++block_updates_;
  tcg_iterations_ += stats.tcg_iterations;
  updated_cost_share_ = stats.cost_share;
  if (stats.tangent) ++tangent_updates_;
  updated_version_ = neighbours_version_;
  return updated_X_;
}

Eigen::MatrixXd AgentState::precondition(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G) {
  const LiftedManifold manifold = problem_.manifold(static_cast<int>(X.rows()));
  if (X.rows() == d_ && tangent_ && tangent_->factored()) return tangent_->apply(manifold, X, G);
  return euclidean().apply(manifold, X, G);
}

bool AgentState::refresh_tangent(const Eigen::MatrixXd& X) {
  return refactor_tangent(X, nullptr);
}

bool AgentState::refresh_tangent(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad) {
  return refactor_tangent(X, &egrad);
}

bool AgentState::refactor_tangent(const Eigen::MatrixXd& X, const Eigen::MatrixXd* egrad) {
  // The Q_BB factor's size decides (a tangent factor would be larger still); when it is not
  // held (released, or the block grew), the answer of its last build stands: building it only
  // to ask would cost a factorization the tangent factor makes unnecessary.
  if (X.rows() != d_ || (precon_ ? precon_->block_diagonal() : block_factor_too_large_))
    return false;
  if (!tangent_) {
    if (!build_tangent(X, BlockUpdateOptions{})) return false;
    if (!egrad) return true;  // factored at X when built
  }
  if (!tangent_->usable()) return false;
  const int before = tangent_->factorizations();
  const bool factored = egrad ? tangent_->factorize(X, *egrad) : tangent_->factorize(X);
  count_tangent_factorizations(before);
  return factored;
}

bool AgentState::ensure_tangent(const Eigen::MatrixXd& X) {
  if (X.rows() == d_ && tangent_ && tangent_->factored()) return true;
  return refresh_tangent(X);
}

bool AgentState::rebuild_grown_tangent(const Eigen::MatrixXd& X) {
  if (X.rows() != d_ || !tangent_ || !tangent_->factored() || tangent_->grown_poses() == 0)
    return false;
  tangent_.reset();
  tangent_tried_ = false;
  return refresh_tangent(X);
}

double AgentState::local_cost(const Eigen::MatrixXd& X, const Eigen::MatrixXd& neighbours) {
  set_point(X, neighbours);
  return problem_.cost(active_part(X));
}

void AgentState::reset_iterate(const Eigen::MatrixXd& Y0, const Eigen::MatrixXd& Yn0) {
  if (Y0.cols() != Y.cols() || Yn0.cols() != Yn.cols() || Yn0.rows() != Y0.rows())
    throw std::invalid_argument("AgentState::reset_iterate: block of the wrong size");
  Y = P = V = Y_prev = V_prev = Y0;
  Yn = Pn = Vn = Yn_prev = Yn0;
  neighbours_set_.resize(0, 0);  // the problem's neighbour poses are stale
  rows_.clear();
  updated_grad_norm_sq_ = -1.0;  // nothing to reuse (and updated_X_ may have another rank)
}

}  // namespace tessera
