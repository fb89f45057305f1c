#pragma once
// Internal: which rows of the lifted space a point occupies.

#include <Eigen/Core>
#include <vector>

namespace tessera {

/// The rows of X (and of `also`, when it has entries) that are non-zero somewhere: the rows a
/// lifted point actually uses. An iterate lifted from dimension d keeps the others at exact
/// zero and every step maps them to zero, so protocols send and work on these rows only.
inline std::vector<Eigen::Index> nonzero_rows(const Eigen::MatrixXd& X,
                                              const Eigen::MatrixXd& also) {
  Eigen::Array<bool, Eigen::Dynamic, 1> nonzero = (X.array() != 0.0).rowwise().any();
  if (also.size() > 0) nonzero = nonzero || (also.array() != 0.0).rowwise().any();
  std::vector<Eigen::Index> rows;
  rows.reserve(static_cast<std::size_t>(X.rows()));
  for (Eigen::Index k = 0; k < X.rows(); ++k)
    if (nonzero(k)) rows.push_back(k);
  return rows;
}

}  // namespace tessera
