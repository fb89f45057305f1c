#pragma once
// sym(A^T B) of one pose's r x D Stiefel blocks A, B (column-major, leading dimension r): the
// per-pose product of the tangent projection (lifted_manifold.cpp) and of the Riemannian
// Hessian's projection (pose_kernels.cpp). For a fixed D and (R > 0) a fixed row count. The
// build's -O2 keeps fixed-count loops rolled (the scratch arrays then live in memory); the unroll
// pragmas (here and in the kernels that call this) cut parking-garage's centralized solve from
// 14.0 to 11.5 G instructions, same results bit for bit.

#include <Eigen/Core>

namespace tessera {

template <int D, int R>
inline void sym_product(const double* A, const double* B, Eigen::Index r, double (&S)[D][D]) {
  const Eigen::Index rr = R > 0 ? R : r;
  double P[D][D];
#pragma GCC unroll 16
  for (int a = 0; a < D; ++a)
#pragma GCC unroll 16
    for (int b = 0; b < D; ++b) {
      double acc = 0.0;
#pragma GCC unroll 16
      for (Eigen::Index k = 0; k < rr; ++k) acc += A[a * rr + k] * B[b * rr + k];
      P[a][b] = acc;
    }
#pragma GCC unroll 16
  for (int a = 0; a < D; ++a)
#pragma GCC unroll 16
    for (int b = 0; b < D; ++b) S[a][b] = 0.5 * (P[a][b] + P[b][a]);
}

}  // namespace tessera
