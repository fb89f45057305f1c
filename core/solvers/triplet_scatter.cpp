#include "solvers/triplet_scatter.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace tessera {

bool TripletScatter::build(Eigen::Index n, const std::vector<int>& rows,
                           const std::vector<int>& cols) {
  n_ = -1;
  where_.clear();
  rows_.clear();
  cols_.clear();
  if (rows.size() != cols.size() || n < 0 || n > std::numeric_limits<int>::max() ||
      rows.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    return false;
  const auto nn = static_cast<std::size_t>(n);
  const std::size_t nnz = rows.size();
  // Two stable counting sorts (by row, then by column): compressed columns with their rows
  // ascending, setFromTriplets' layout, in O(entries + n).
  std::vector<int> row_start(nn + 1, 0), col_start(nn + 1, 0);
  for (std::size_t k = 0; k < nnz; ++k) {
    if (rows[k] < 0 || rows[k] >= n || cols[k] < 0 || cols[k] >= n) return false;
    ++row_start[static_cast<std::size_t>(rows[k]) + 1];
    ++col_start[static_cast<std::size_t>(cols[k]) + 1];
  }
  for (std::size_t i = 0; i < nn; ++i) {
    row_start[i + 1] += row_start[i];
    col_start[i + 1] += col_start[i];
  }
  std::vector<int> by_row(nnz);
  for (std::size_t k = 0; k < nnz; ++k)
    by_row[static_cast<std::size_t>(row_start[static_cast<std::size_t>(rows[k])]++)] =
        static_cast<int>(k);
  SparseMatrix& m = matrix_;  // written in place (SparseMatrix assignment copies)
  m.resize(n, n);
  m.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  std::copy(col_start.begin(), col_start.end(), m.outerIndexPtr());
  std::vector<int> where(nnz);
  int* inner = m.innerIndexPtr();
  for (int k : by_row) {
    const auto c = static_cast<std::size_t>(cols[static_cast<std::size_t>(k)]);
    const int at = col_start[c]++;
    inner[at] = rows[static_cast<std::size_t>(k)];
    where[static_cast<std::size_t>(k)] = at;
  }
  // A position twice: the same row next to itself in its column.
  for (Eigen::Index j = 0; j < n; ++j)
    for (int a = m.outerIndexPtr()[j] + 1; a < m.outerIndexPtr()[j + 1]; ++a)
      if (inner[a] == inner[a - 1]) {
        m = SparseMatrix();
        return false;
      }
  std::fill(m.valuePtr(), m.valuePtr() + nnz, 0.0);
  n_ = n;
  rows_ = rows;
  cols_ = cols;
  where_ = std::move(where);
  return true;
}

bool TripletScatter::matches(Eigen::Index n, const std::vector<int>& rows,
                             const std::vector<int>& cols) const {
  return n_ >= 0 && n == n_ && rows == rows_ && cols == cols_;
}

bool TripletScatter::assign(Eigen::Index n, const std::vector<Eigen::Triplet<double>>& entries) {
  bool same = n_ >= 0 && n == n_ && entries.size() == rows_.size();
  for (std::size_t k = 0; same && k < entries.size(); ++k)
    same = entries[k].row() == rows_[k] && entries[k].col() == cols_[k];
  if (!same) {
    std::vector<int> rows(entries.size()), cols(entries.size());
    for (std::size_t k = 0; k < entries.size(); ++k) {
      rows[k] = static_cast<int>(entries[k].row());
      cols[k] = static_cast<int>(entries[k].col());
    }
    if (!build(n, rows, cols)) return false;
  }
  double* v = matrix_.valuePtr();
  for (std::size_t k = 0; k < entries.size(); ++k) v[where_[k]] = entries[k].value();
  return true;
}

void TripletScatter::fill(const std::vector<double>& values) {
  fill(values.data(), values.size());
}

void TripletScatter::fill(const double* values, std::size_t count) {
  if (n_ < 0 || count != where_.size())
    throw std::logic_error("TripletScatter::fill: values do not match the pattern");
  double* v = matrix_.valuePtr();
  for (std::size_t k = 0; k < count; ++k) v[where_[k]] = values[k];
}

}  // namespace tessera
