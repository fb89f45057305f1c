#pragma once
// The Frobenius inner product <A, B> = sum_ij A_ij B_ij = tr(A^T B) of two same-shape matrices:
// the inner product of the lifted problem's ambient space, which the conjugate gradients and
// the preconditioned gradient norms take. Eigen's element-wise product summed by its vectorised
// reduction; one definition, so that every caller sums in the same order.

#include <Eigen/Core>

namespace tessera {

inline double frobenius_inner(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) {
  return A.cwiseProduct(B).sum();
}

}  // namespace tessera
