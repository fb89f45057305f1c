#pragma once
// The smoothed coarse space of the two-level rounds (CoarseSpaceKind::kSmoothed): smoothed
// aggregation for the pose graph. The slow error of block updates is smooth bending of the
// map (the rotation varying across it, the translations following), not a rigid drift of
// whole blocks: measured on the generated 8000-pose grid at N = 49, one correction with one
// rigid motion per block removes 6 % of f - f*, with 16 rigid pieces per block 29 %, with the
// same pieces blended smoothly 64-79 % (docs/irbcd.md, "Coarse correction").
//
// The space: each block's own graph is cut into `aggregates` pieces grown by BFS (a block
// whose own graph falls apart gets a piece per part); every piece alpha may move rigidly,
// Z_alpha = [G_alpha c_alpha]; pose i moves by the blend X_i -> sum_alpha w_i,alpha Z_alpha
// [X_i; 0 1] of the pieces' motions, with weights w_i (a partition of unity) from the pieces'
// indicator functions smoothed by Jacobi steps of the graph Laplacian over the whole graph,
// across block borders too. Each edge's residual is linear in the Z's, so f after the blend is
// tr(Z Q_c Z^T) exactly, with Q_c summed edge by edge: the same small problem as the block
// space, over the pieces instead of the blocks. A blended Y_i is not orthonormal; it is put
// back on the manifold by its polar factor (second order in the step: measured, the decrease
// of f equals the model's to 1 %), so the iterate stays feasible and the certificate is
// unaffected.
//
// Every agent builds the same space from the graph's structure (endpoints) and the partition,
// so the pieces, weights and the layout of everyone's terms need no message.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/graph/measurement.hpp>
#include <utility>
#include <vector>

namespace tessera {

struct CoarseSpace {
  int num_blocks = 0;
  int num_aggregates = 0;
  std::vector<int> aggregate_block;  ///< Block of every aggregate (aggregates numbered by block).
  std::vector<int> owner;            ///< Block of every pose.
  std::vector<int> aggregate;        ///< Aggregate of every pose before smoothing.
  /// Smoothed weights of pose i: weight_aggregate / weight over [weight_start[i],
  /// weight_start[i+1]), aggregates ascending, summing to 1.
  std::vector<std::size_t> weight_start;
  std::vector<int> weight_aggregate;
  std::vector<double> weight;
  /// The aggregate pairs (alpha <= beta, ascending) of agent a's coarse terms:
  /// pairs[pair_start[a] .. pair_start[a+1]).
  std::vector<std::size_t> pair_start;
  std::vector<std::pair<int, int>> pairs;

  /// Whether agent `agent` sums the edge (i, j): its own inside edges and the cut edges to
  /// higher-numbered blocks.
  bool sums_edge(int agent, std::size_t i, std::size_t j) const;
  /// An edge whose both ends move by the same single rigid motion: its residual's norm never
  /// changes, so it is left out of Q_c.
  bool rigid_invariant(std::size_t i, std::size_t j) const;
  /// Bytes its lists hold (their capacities): every agent keeps the whole graph's
  /// (docs/scale.md, "The memory model").
  std::size_t bytes() const;
};

/// Builds the space of `options` (aggregates, smoothing_steps, smoothing_weight) from the
/// graph's edges and the block of every pose. Deterministic.
CoarseSpace make_coarse_space(std::size_t num_poses,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges,
                              const std::vector<int>& assignment, const CoarseOptions& options);
/// The same from full measurements.
CoarseSpace make_coarse_space(std::size_t num_poses, const std::vector<Measurement>& measurements,
                              const std::vector<int>& assignment, const CoarseOptions& options);

/// One agent's edges of the smoothed coarse problem and the terms they give at a point.
class SmoothedCoarseTerms {
 public:
  /// `owned`, `neighbours`: the block's poses and neighbour poses (BlockProblem order).
  SmoothedCoarseTerms(const CoarseSpace& space, int id, int d,
                      const std::vector<std::size_t>& owned,
                      const std::vector<std::size_t>& neighbours,
                      const std::vector<Measurement>& measurements);

  /// Layout: a bit mask of the rows k < r that X or Xn use; with I = those rows and row r,
  /// for each of the agent's pairs (CoarseSpace::pairs order) Q_alpha,beta on I x I: the upper
  /// triangle column by column when alpha = beta, else the whole block column-major.
  std::vector<double> compute(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn) const;

  /// Bytes held (lists' capacities and each edge's R and t): grows with the agent's edges.
  std::size_t bytes() const;

 private:
  // One piece in the blend of an edge's ends: its weight at the target j and at the source i
  // (0 where the piece is not in that end's blend).
  struct Piece {
    bool at_j, at_i;
    double w_j, w_i;
  };
  struct Edge {
    bool i_own, j_own;  // whether the source / target is an own pose (else a neighbour copy)
    std::size_t i_slot, j_slot;
    Eigen::MatrixXd R;
    Eigen::VectorXd t;
    double kappa, tau;
    // The pieces of both ends (aggregates ascending) and, for each piece pair p <= q in that
    // order, its index among the agent's pairs: fixed by the space, so found once here.
    std::size_t piece_begin, piece_end, pair_begin;
  };
  const CoarseSpace& space_;
  int id_;
  int d_;
  std::vector<Edge> edges_;
  std::vector<Piece> pieces_;
  std::vector<std::size_t> pair_index_;
  std::size_t max_pieces_ = 0;
};

/// Solves the smoothed coarse problem from every agent's terms (agent-id order). motions[alpha]
/// per aggregate, r x (r+1). Throws std::runtime_error on a malformed term vector.
CoarseResult solve_smoothed_coarse(const CoarseSpace& space, int r,
                                   const std::vector<const std::vector<double>*>& terms,
                                   const CoarseOptions& options);

/// Moves the poses `ids` (global ids of X's columns, in order) by their blended motions and
/// puts each Y_i back on the manifold (polar factor); a pose of one aggregate moves rigidly.
void apply_blended_motions(const CoarseSpace& space, const std::vector<Eigen::MatrixXd>& motions,
                           int d, const std::vector<std::size_t>& ids, Eigen::MatrixXd& X);
/// The same for an iterate X and its momentum V (the same poses, same shape): where a pose of
/// V equals X's (bit for bit), V gets X's moved pose, computed once.
void apply_blended_motions(const CoarseSpace& space, const std::vector<Eigen::MatrixXd>& motions,
                           int d, const std::vector<std::size_t>& ids, Eigen::MatrixXd& X,
                           Eigen::MatrixXd& V);

}  // namespace tessera
