#pragma once
// The coarse level of the rounding's translation preconditioner: one translation offset per
// block (Nicolaides' coarse space, Z_k = the indicator of block k's free poses), added to the
// block-Jacobi solve, M = B + Z E^-1 Z^T with E = Z^T L Z (two-level additive Schwarz).
// Why: block Jacobi moves information one block boundary per CG step, so its steps grow with
// the number of blocks and the block graph's diameter; a warm start after few rounds is off
// mostly by smooth, block-sized shifts, which Z E^-1 Z^T removes in one application.
//
// E is N x N (N = agents): every agent knows its own row (its block's coupling to the others)
// and, after one all-gather, factorises the whole E redundantly, so no agent is central. Each
// application needs Z^T w over all blocks; the CG carries it by a recurrence whose terms each
// agent computes from its own rows (block_sums, coupling_sums), so it rides on the step's one
// all-gather instead of adding a message step.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

namespace tessera::agent {

class RoundingCoarse {
 public:
  /// L_own / L_nb: the agent's rows of the translation Laplacian on its own and on its
  /// neighbours' poses (columns); nb_block: the block of each L_nb column; free_row: whether
  /// the own row is a free pose (not the anchor pose 0).
  RoundingCoarse(const Eigen::SparseMatrix<double>& L_own, const Eigen::SparseMatrix<double>& L_nb,
                 const std::vector<std::uint32_t>& nb_block, const std::vector<bool>& free_row,
                 std::uint32_t self, std::uint32_t blocks);

  /// Blocks this agent's rows couple to (itself included), ascending: the non-zero rows of
  /// coupling_sums() and of own_row().
  const std::vector<std::uint32_t>& touched() const { return touched_; }

  /// This block's row of E = Z^T L Z (length N).
  Eigen::VectorXd own_row() const;

  /// Factorises E assembled from every block's row (symmetrised; a block without free poses
  /// gets a unit diagonal, its offset is never used). False when E is not positive definite
  /// (the block graph does not reach the anchor): then the CG runs without the coarse level.
  bool factorise(Eigen::MatrixXd E);

  /// E^-1 c and E y for N x d matrices.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& c) const { return llt_.solve(c); }
  Eigen::MatrixXd times(const Eigen::MatrixXd& y) const { return E_ * y; }

  /// Z_self^T v: the sum of v over this block's free rows (1 x d).
  Eigen::RowVectorXd block_sum(const Eigen::MatrixXd& v) const;

  /// (L Z)_own^T v: this agent's share of Z^T L v for v supported on its rows (N x d).
  Eigen::MatrixXd coupling_sums(const Eigen::MatrixXd& v) const { return AZ_.transpose() * v; }

  /// v + Z y on this block's rows: each free row shifted by the block's offset y.row(self).
  void add_offset(Eigen::MatrixXd& v, const Eigen::MatrixXd& y) const;

 private:
  std::uint32_t self_;
  std::vector<bool> free_row_;
  Eigen::SparseMatrix<double> AZ_;  // (L Z) on this agent's rows, m x N
  std::vector<std::uint32_t> touched_;
  Eigen::MatrixXd E_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
};

}  // namespace tessera::agent
