#pragma once
// The lifted PGO objective restricted to a block of poses, with the poses of neighbouring
// blocks held fixed. The centralized problem is the block that owns every pose (no
// neighbours); a distributed agent's local problem is the block of its partition.
//
// With X the block's lifted poses (owned order) and X_N the neighbours' (neighbor order):
//   f_B(X) = tr(X Q_BB X^T) + 2 tr(X Q_BN X_N^T) + tr(X_N Q_NN X_N^T),
// i.e. the full reference objective summed over every measurement touching the block.

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <tessera/graph/measurement.hpp>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/problem/data_matrix.hpp>
#include <tessera/problem/pose_block_matrix.hpp>
#include <unordered_map>
#include <vector>

namespace tessera {

class BlockProblem {
 public:
  /// `owned`: global ids of the block's poses (any order; kept as given). Measurements not
  /// touching an owned pose are ignored; a measurement's other endpoint, when not owned,
  /// becomes a neighbour pose. Neighbours are ordered by global id.
  BlockProblem(int d, std::vector<std::size_t> owned, const std::vector<Measurement>& measurements);

  /// Grows the problem in place to what the constructor would build from the owned poses
  /// followed by `new_owned` and `measurements` (a growing graph: its first `first_new`
  /// measurements are the ones this problem was built or last extended from, in the same order).
  /// Only measurements[first_new, end) are read, so the cost is that of the new data plus a pass
  /// over this block's own entries, not a scan of the whole graph. `new_owned` must be poses no
  /// earlier measurement touches (new poses of the graph): a pose that moves in from another
  /// block needs a new problem (std::invalid_argument when it is one of the neighbours).
  /// Neighbours stay ordered by id. The neighbours' poses must be set again afterwards.
  /// Q_BB and Q_NB equal the rebuilt ones up to the order of floating-point additions.
  void extend(const std::vector<std::size_t>& new_owned,
              const std::vector<Measurement>& measurements, std::size_t first_new);

  /// The centralized problem: every pose 0..n-1 owned.
  static BlockProblem whole_graph(int d, std::size_t num_poses,
                                  const std::vector<Measurement>& measurements);

  int dim() const { return d_; }
  const std::vector<std::size_t>& owned() const { return owned_; }
  const std::vector<std::size_t>& neighbors() const { return neighbors_; }
  std::size_t num_owned() const { return owned_.size(); }
  std::size_t num_neighbors() const { return neighbors_.size(); }
  /// Measurements touching the block (internal and cut).
  std::size_t num_measurements() const { return edges_.size(); }
  /// Q_BB: the quadratic form on the block's own poses.
  const SparseMatrix& data_matrix() const { return Q_bb_; }
  /// Q_NB: the cut measurements' coupling, (d+1)k neighbour rows x (d+1)m owned columns.
  const SparseMatrix& neighbor_matrix() const { return Q_nb_; }
  LiftedManifold manifold(int r) const { return LiftedManifold(r, d_, owned_.size()); }
  /// Keeps Q_BB also as dense pose blocks (PoseBlockMatrix), which the products of the
  /// gradient and the Hessian then read: the same values, about a third fewer instructions
  /// for those products, and ~1 KB more memory per pose in 3D (0.9 KB in 2D). The agents'
  /// rounds use it; extend() keeps it. Bytes held: pose_blocks_bytes().
  void use_pose_blocks();
  std::size_t pose_blocks_bytes() const { return Q_bb_blocks_ ? Q_bb_blocks_->bytes() : 0; }

  /// Fixes the neighbours' lifted poses (r x (d+1)k, neighbors() order). Must be called
  /// before evaluating a block with neighbours, and again whenever they change.
  void set_neighbor_poses(const Eigen::MatrixXd& X_neighbors);
  const Eigen::MatrixXd& neighbor_poses() const { return X_n_; }

  /// f_B(X) as above. With `share` not null, also cost_share(X) (the same edge terms summed
  /// in the same order, so bit-identical to calling it).
  double cost(const Eigen::MatrixXd& X, double* share = nullptr) const;
  /// Euclidean gradient 2 (X Q_BB + X_N Q_NB).
  Eigen::MatrixXd euclidean_gradient(const Eigen::MatrixXd& X) const;
  /// The same with other neighbour poses `X_neighbors` (neighbors() order) than the ones set,
  /// which stay set: a reader of a shared problem (the certificate's vectors) needs no copy of
  /// it. Bit-identical to set_neighbor_poses(X_neighbors) then euclidean_gradient(X).
  Eigen::MatrixXd euclidean_gradient(const Eigen::MatrixXd& X,
                                     const Eigen::MatrixXd& X_neighbors) const;
  /// Riemannian gradient on the block's manifold.
  Eigen::MatrixXd riemannian_gradient(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad) const;
  /// The same, projecting egrad in its own storage (no copy; the same values).
  Eigen::MatrixXd riemannian_gradient(const Eigen::MatrixXd& X, Eigen::MatrixXd&& egrad) const;
  /// Riemannian Hessian applied to tangent V at X (egrad = Euclidean gradient at X).
  Eigen::MatrixXd hessian_vector(const Eigen::MatrixXd& X, const Eigen::MatrixXd& egrad,
                                 const Eigen::MatrixXd& V) const;

  /// This block's share of the global cost: internal measurements in full, cut measurements
  /// half (the other half is counted by the neighbour's block), so shares sum to f exactly.
  double cost_share(const Eigen::MatrixXd& X) const;

 private:
  struct Edge {
    std::size_t slot_i, slot_j;  // local slots: owned first, then neighbours
  };
  // Sum over the block's measurements of their terms at X; `share` (if not null) receives the
  // same sum with the cut ones halved.
  double edge_sum(const Eigen::MatrixXd& X, double* share) const;
  template <int D, int R>
  double sum_edges(const Eigen::MatrixXd& X, double* share) const;

  int d_;
  std::vector<std::size_t> owned_;
  // Slot of each owned id, built on the first extend() (the constructor does not need it).
  std::unordered_map<std::size_t, std::size_t> owned_slot_;
  std::vector<std::size_t> neighbors_;
  std::vector<Edge> edges_;
  // Per edge, in edges_ order: R (column-major), t, kappa, tau. The problem's only copy of
  // its measurements (so it outlives its input): the cost loops read them contiguously.
  std::vector<double> packed_;
  SparseMatrix Q_bb_;
  SparseMatrix Q_nb_;                           // (d+1)k x (d+1)m
  std::optional<PoseBlockMatrix> Q_bb_blocks_;  // Q_bb_ by pose blocks (use_pose_blocks)
  // out = scale X Q_BB, by pose blocks when held.
  void times_own(const Eigen::MatrixXd& X, double scale, Eigen::MatrixXd& out) const;
  Eigen::MatrixXd X_n_;
  Eigen::MatrixXd linear_;  // X_N Q_NB, r x (d+1)m
};

}  // namespace tessera
