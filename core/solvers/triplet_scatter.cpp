#include "solvers/triplet_scatter.hpp"

#include <stdexcept>

namespace tessera {

bool TripletScatter::build(Eigen::Index n, const std::vector<int>& rows,
                           const std::vector<int>& cols) {
  n_ = -1;
  where_.clear();
  rows_.clear();
  cols_.clear();
  matrix_ = SparseMatrix();
  if (rows.size() != cols.size() || n < 0) return false;
  // Each entry's value is its own index (exact in a double below 2^53): after setFromTriplets
  // the value at each place says which entry went there.
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (rows[k] < 0 || rows[k] >= n || cols[k] < 0 || cols[k] >= n) return false;
    t.emplace_back(rows[k], cols[k], static_cast<double>(k));
  }
  SparseMatrix m(n, n);
  m.setFromTriplets(t.begin(), t.end());
  if (static_cast<std::size_t>(m.nonZeros()) != rows.size()) return false;  // a repeat
  std::vector<Eigen::Index> where(rows.size(), -1);
  const double* v = m.valuePtr();
  for (Eigen::Index i = 0; i < m.nonZeros(); ++i) {
    const auto k = static_cast<std::size_t>(v[i]);
    if (k >= where.size() || where[k] >= 0) return false;
    where[k] = i;
  }
  n_ = n;
  rows_ = rows;
  cols_ = cols;
  where_ = std::move(where);
  matrix_ = std::move(m);
  return true;
}

bool TripletScatter::matches(Eigen::Index n, const std::vector<int>& rows,
                             const std::vector<int>& cols) const {
  return n_ >= 0 && n == n_ && rows == rows_ && cols == cols_;
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
