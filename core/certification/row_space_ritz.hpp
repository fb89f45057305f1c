#pragma once
// The smallest Ritz value of S on the row space of the iterate Y (r x N): at a critical point
// S Y^T = 0, so Y's rows are S's null space and this is lambda_min(S) up to the residual. From
// three r x r Gram matrices, which an agent sums over the blocks (distributed certificate) or
// the centralized certificate forms at once: Y Y^T, Y S Y^T and (Y S)(Y S)^T.

#include <Eigen/Core>

namespace tessera {

struct RowSpaceRitz {
  Eigen::VectorXd coefficients;  ///< c: the Ritz vector is c^T Y, with c^T Y Y^T c = 1.
  double theta = 0.0;            ///< Its Rayleigh quotient (>= lambda_min(S)).
  double residual = 0.0;         ///< ||c^T Y S - theta c^T Y||.
};

/// The smallest eigenpair of the pencil (a, b), b symmetric positive semidefinite: a x = theta b x
/// on the span of b's eigenvectors whose eigenvalue is above 1e-10 of its largest, x with
/// x^T b x = 1. The Rayleigh-Ritz step of row_space_ritz and of the distributed LOBPCG.
struct PencilPair {
  Eigen::VectorXd vector;
  double value = 0.0;
};
PencilPair smallest_pencil_pair(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b);

/// Rayleigh-Ritz on the rows of Y (directions with Y Y^T eigenvalue below 1e-10 of its largest
/// dropped). `yy` = Y Y^T, `ysy` = Y S Y^T, `ss` = (Y S)(Y S)^T.
RowSpaceRitz row_space_ritz(const Eigen::MatrixXd& yy, const Eigen::MatrixXd& ysy,
                            const Eigen::MatrixXd& ss);

}  // namespace tessera
