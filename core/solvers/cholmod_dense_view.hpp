#pragma once
// A cholmod_dense header over an Eigen vector's storage (no copy), the right-hand side that
// cholmod_solve2 reads.

#include <Eigen/CholmodSupport>
#include <cstddef>

namespace tessera {

inline cholmod_dense cholmod_dense_view(Eigen::VectorXd& v) {
  cholmod_dense d;
  d.nrow = static_cast<std::size_t>(v.size());
  d.ncol = 1;
  d.nzmax = d.nrow;
  d.d = d.nrow;
  d.x = v.data();
  d.z = nullptr;
  d.xtype = CHOLMOD_REAL;
  d.dtype = CHOLMOD_DOUBLE;
  return d;
}

}  // namespace tessera
