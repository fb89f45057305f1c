#pragma once
// A cholmod_dense header over an Eigen vector's storage (no copy), the right-hand side that
// cholmod_solve2 reads.

#include <Eigen/CholmodSupport>
#include <cstddef>

namespace tessera {

/// `n` values at `x` as one column; CHOLMOD's solves only read a right-hand side, hence the
/// const_cast.
inline cholmod_dense cholmod_dense_view(const double* x, Eigen::Index n) {
  cholmod_dense d;
  d.nrow = static_cast<std::size_t>(n);
  d.ncol = 1;
  d.nzmax = d.nrow;
  d.d = d.nrow;
  d.x = const_cast<double*>(x);
  d.z = nullptr;
  d.xtype = CHOLMOD_REAL;
  d.dtype = CHOLMOD_DOUBLE;
  return d;
}

inline cholmod_dense cholmod_dense_view(Eigen::VectorXd& v) {
  return cholmod_dense_view(v.data(), v.size());
}

}  // namespace tessera
