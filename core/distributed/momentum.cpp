#include "distributed/momentum.hpp"

#include <Eigen/Eigenvalues>

namespace tessera {
namespace {

// Proj_M pose by pose. The polar factor of an r x d block A is A (A^T A)^{-1/2}; with d <= 3
// the d x d eigen-decomposition is fixed-size (no heap), several times cheaper than an SVD of
// A, and these projections run on every pose of every agent each round.
template <int D>
void project_poses(Eigen::MatrixXd& X, int d) {
  using Small = Eigen::Matrix<double, D, D>;
  const Eigen::Index n = X.cols() / (d + 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    auto A = X.middleCols((d + 1) * i, d);
    const Small B = A.transpose() * A;
    Eigen::SelfAdjointEigenSolver<Small> es(B);
    const auto& l = es.eigenvalues();
    if (!(l(0) > 1e-12 * l(D - 1))) {  // (nearly) rank deficient: take the SVD's choice
      A = polar_factor(Eigen::MatrixXd(A));
      continue;
    }
    const Small inv_sqrt = es.eigenvectors() * l.cwiseSqrt().cwiseInverse().asDiagonal() *
                           es.eigenvectors().transpose();
    Eigen::Matrix<double, Eigen::Dynamic, D> out = A * inv_sqrt;
    A = out;
  }
}

Eigen::MatrixXd project(const LiftedManifold& M, Eigen::MatrixXd X) {
  if (M.dim() == 2)
    project_poses<2>(X, 2);
  else
    project_poses<3>(X, 3);
  return X;
}

}  // namespace

Eigen::MatrixXd extrapolate(const LiftedManifold& M, const MomentumCoefficients& c,
                            const Eigen::MatrixXd& Y, const Eigen::MatrixXd& V) {
  return project(M, c.alpha * V + (1.0 - c.alpha) * Y);
}

Eigen::MatrixXd momentum_update(const LiftedManifold& M, const MomentumCoefficients& c,
                                const Eigen::MatrixXd& V, const Eigen::MatrixXd& P,
                                const Eigen::MatrixXd& Y_new) {
  return project(M, c.beta * V + (1.0 - c.beta) * P + c.gamma * (Y_new - P));
}

}  // namespace tessera
