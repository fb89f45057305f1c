#pragma once
// Bringing a staircase's higher-rank point back to the online run's rank. The online iterate
// keeps rank r from step to step (its agents' states, factors and messages are sized for it).
// When a certificate taken while the graph grows fails, the staircase leaves the critical point
// along a direction of negative curvature at rank r + 1 and solves there; on the exact
// relaxations of usual pose graphs the certified optimum it reaches has rank d <= r, so it is
// expressed in r rows without changing any residual, and the run goes on from it at rank r.

#include <Eigen/Core>

namespace tessera {

/// The point of rank `r` (r x (d+1)n) nearest to X along X's top-r principal subspace: the
/// common offset of the translations (a gauge freedom of the cost) removed, X's rows expressed
/// in the basis of the top-r eigenvectors of sum_i (Y_i Y_i^T + p_i p_i^T), each Y_i replaced by
/// its polar factor. When X has rank at most r after centring (a rank-d optimum) every residual,
/// hence the cost, is kept. Requires 2 <= d <= r <= X.rows(); r = X.rows() returns X. Throws
/// std::invalid_argument otherwise.
Eigen::MatrixXd project_to_rank(const Eigen::MatrixXd& X, int d, int r);

}  // namespace tessera
