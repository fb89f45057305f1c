#include "distributed/momentum.hpp"

#include <Eigen/Eigenvalues>
#include <utility>

namespace tessera {
namespace {

// Proj_M pose by pose. The polar factor of an r x d block A is A (A^T A)^{-1/2}. The points
// projected here (convex combinations of nearby manifold points) are close to the manifold, so
// B = A^T A is close to I and the coupled Newton-Schulz iteration for B^{-1/2}
// (Y <- Y T, Z <- T Z, T = (3I - Z Y)/2; Y -> I, Z -> B^{-1/2}) converges quadratically in a few
// d x d products. That is several times cheaper than the d x d eigen-decomposition (whose
// iterative QR was ~10% of a round's CPU time), which stays as the fallback for points far
// from the manifold, and the SVD for (nearly) rank-deficient ones. Everything lives on the
// stack: these projections run on every pose of every agent each round.
template <int D>
bool newton_schulz_inv_sqrt(const Eigen::Matrix<double, D, D>& B, Eigen::Matrix<double, D, D>& Z) {
  using Small = Eigen::Matrix<double, D, D>;
  const Small I = Small::Identity();
  if (!((B - I).norm() < 0.5)) return false;
  Small Y = B;
  Z = I;
  for (int it = 0; it < 12; ++it) {
    const Small E = I - Z * Y;
    const double e = E.norm();
    const Small T = I + 0.5 * E;
    Y = (Y * T).eval();
    Z = (T * Z).eval();
    if (e < 1e-9) return true;  // quadratic convergence: this last step took it to ~1e-17
  }
  return false;
}

template <int D>
void project_poses(Eigen::MatrixXd& X, int d) {
  using Small = Eigen::Matrix<double, D, D>;
  const Eigen::Index n = X.cols() / (d + 1);
  const Eigen::Index r = X.rows();
  double tmp[D * 64];
  for (Eigen::Index i = 0; i < n; ++i) {
    auto A = X.middleCols((d + 1) * i, d);
    const Small B = A.transpose() * A;
    Small inv_sqrt;
    if (!newton_schulz_inv_sqrt<D>(B, inv_sqrt)) {
      Eigen::SelfAdjointEigenSolver<Small> es(B);
      const auto& l = es.eigenvalues();
      if (!(l(0) > 1e-12 * l(D - 1))) {  // (nearly) rank deficient: take the SVD's choice
        A = polar_factor(Eigen::MatrixXd(A));
        continue;
      }
      inv_sqrt = es.eigenvectors() * l.cwiseSqrt().cwiseInverse().asDiagonal() *
                 es.eigenvectors().transpose();
    }
    if (r <= 64) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, D>> out(tmp, r, D);
      out.noalias() = A * inv_sqrt;
      A = out;
    } else {
      Eigen::Matrix<double, Eigen::Dynamic, D> out = A * inv_sqrt;
      A = out;
    }
  }
}

}  // namespace

Eigen::MatrixXd project_to_manifold(const LiftedManifold& M, Eigen::MatrixXd X) {
  if (M.dim() == 2)
    project_poses<2>(X, 2);
  else
    project_poses<3>(X, 3);
  return X;
}

namespace {
Eigen::MatrixXd project(const LiftedManifold& M, Eigen::MatrixXd X) {
  return project_to_manifold(M, std::move(X));
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
