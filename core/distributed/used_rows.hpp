#pragma once
// Internal: which rows of the lifted space an agent's poses occupy.

#include <Eigen/Core>
#include <vector>

namespace tessera {

/// The rows k of X that are non-zero in X or, when it has columns, in the neighbour copies Xn
/// (same row count). An iterate lifted from dimension d keeps r - d rows at exact zero, and
/// every step maps them to zero: protocols send and work on the other rows only.
inline std::vector<int> used_rows(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn) {
  std::vector<int> rows;
  for (Eigen::Index k = 0; k < X.rows(); ++k)
    if ((X.row(k).array() != 0.0).any() || (Xn.cols() > 0 && (Xn.row(k).array() != 0.0).any()))
      rows.push_back(static_cast<int>(k));
  return rows;
}

}  // namespace tessera
