#pragma once
// A sparse matrix made of w x w blocks (w = d + 1, one block row and column per pose), stored
// block column by block column with every block dense: the data matrix Q_BB as the products
// X Q of an agent's rounds read it. The CSC form loads a row index and computes an address per
// non-zero; here one index serves a whole block and a pose's slice of X is read once per block.
// An entry the CSC form does not hold is an explicit 0 here: the products add 0 * x to a sum
// that starts at +0, which changes no value (x finite), so X Q equals
// scaled_dense_times_sparse's to the last bit (each output column summed in the same order).

#include <Eigen/Core>
#include <cstddef>
#include <tessera/problem/data_matrix.hpp>
#include <vector>

namespace tessera {

class PoseBlockMatrix {
 public:
  PoseBlockMatrix() = default;
  /// Q: (w n) x (w m), every non-zero inside a w x w block of the pose grid. Throws
  /// std::invalid_argument when a dimension is not a multiple of w.
  PoseBlockMatrix(const SparseMatrix& Q, int w);

  int block_size() const { return w_; }
  Eigen::Index rows() const { return rows_; }
  Eigen::Index cols() const { return w_ * static_cast<Eigen::Index>(start_.size() - 1); }
  /// Blocks held (explicit zeros included): w^2 doubles and one index each.
  std::size_t num_blocks() const { return row_block_.size(); }
  std::size_t bytes() const;

  /// out = scale * X * Q (X: r x rows(), out resized to r x cols()): bit-identical to
  /// scaled_dense_times_sparse(X, Q, scale, out) for finite X.
  void times(const Eigen::MatrixXd& X, double scale, Eigen::MatrixXd& out) const;

 private:
  int w_ = 0;
  Eigen::Index rows_ = 0;
  std::vector<std::size_t> start_{0};  // blocks of block column J: start_[J] .. start_[J+1]-1
  std::vector<int> row_block_;         // block row of each block, increasing within a column
  std::vector<double> values_;         // w^2 per block, row-major (entry (p, q) at p w + q)
};

}  // namespace tessera
