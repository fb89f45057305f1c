#pragma once
// Internal: which rows of the lifted space a point occupies.

#include <Eigen/Core>
#include <vector>

namespace tessera {

/// Whether row k of M has a non-zero entry.
inline bool row_has_nonzero(const Eigen::MatrixXd& M, Eigen::Index k) {
  // Strided down row k, four columns a test: a used row stops at its first column, an unused
  // one (the common case) is read to the end.
  const Eigen::Index r = M.rows(), n = M.cols();
  const double* m = M.data() + k;
  Eigen::Index j = 0;
  for (; j + 4 <= n; j += 4, m += 4 * r)
    if ((m[0] != 0.0) | (m[r] != 0.0) | (m[2 * r] != 0.0) | (m[3 * r] != 0.0)) return true;
  for (; j < n; ++j, m += r)
    if (*m != 0.0) return true;
  return false;
}

/// The rows of X (and of `also`, when it has entries) that are non-zero somewhere: the rows a
/// lifted point actually uses. An iterate lifted from dimension d keeps the others at exact
/// zero and every step maps them to zero, so protocols send and work on these rows only.
inline std::vector<Eigen::Index> nonzero_rows(const Eigen::MatrixXd& X,
                                              const Eigen::MatrixXd& also) {
  std::vector<Eigen::Index> rows;
  rows.reserve(static_cast<std::size_t>(X.rows()));
  for (Eigen::Index k = 0; k < X.rows(); ++k)
    if (row_has_nonzero(X, k) || (also.size() > 0 && row_has_nonzero(also, k))) rows.push_back(k);
  return rows;
}

}  // namespace tessera
