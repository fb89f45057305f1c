#pragma once
// A sparse matrix assembled again and again from entries at the same positions, listed in the
// same order (a factorization whose pattern does not change from point to point: the Newton
// refinement's block Hessians and its interface matrix Sigma). The positions are sorted into
// compressed columns once (two counting sorts: the layout of Eigen's setFromTriplets); each
// later assembly writes every value straight to its place. No position may repeat (no entries are
// summed), so the matrix is the one setFromTriplets would build from the same entries, to the bit,
// explicit zeros included. On city10000 at N = 5 (in process, callgrind) setFromTriplets was 112 M
// of the refinement's 1.95 G instructions, sorting the same ~100k positions at each of the three
// points.

#include <Eigen/SparseCore>
#include <cstddef>
#include <tessera/problem/data_matrix.hpp>
#include <vector>

namespace tessera {

class TripletScatter {
 public:
  /// Sets the pattern: an n x n matrix with an entry at each (rows[k], cols[k]), k-th value
  /// in fill()'s order. False (nothing held) where a position repeats or is out of range.
  bool build(Eigen::Index n, const std::vector<int>& rows, const std::vector<int>& cols);
  /// Whether a pattern is held (the last build() returned true).
  bool built() const { return n_ >= 0; }
  /// Whether the pattern was built (build() returned true) from exactly these positions.
  bool matches(Eigen::Index n, const std::vector<int>& rows, const std::vector<int>& cols) const;
  /// Writes values[k] to the place of the k-th position (values.size() == the positions').
  /// The matrix keeps its pattern: the previous values are all overwritten.
  void fill(const std::vector<double>& values);
  void fill(const double* values, std::size_t count);
  /// build() from the entries' positions unless the pattern already holds exactly those (same
  /// n, same positions in the same order), then fill() with their values: the values of a
  /// pattern seen before are written without copying the positions out. False (nothing held)
  /// where build() fails.
  bool assign(Eigen::Index n, const std::vector<Eigen::Triplet<double>>& entries);
  /// The assembled matrix (compressed columns, rows sorted within each column).
  const SparseMatrix& matrix() const { return matrix_; }

 private:
  Eigen::Index n_ = -1;
  std::vector<int> rows_, cols_;  // the positions, in the callers' order
  std::vector<int> where_;        // k-th position -> its index in matrix_'s values
  SparseMatrix matrix_;
};

}  // namespace tessera
