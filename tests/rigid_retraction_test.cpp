// The Newton refinement's retraction (core/distributed/rigid_retraction.hpp): a twist shared by
// every pose moves them rigidly whatever the angle (where the polar retraction with additive
// translations stretches the map), a small step is followed to first order, and a rank-lifted
// point falls back to the polar retraction.

#include "distributed/rigid_retraction.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <tessera/manifold/lifted_manifold.hpp>

namespace tessera {
namespace {

// n poses in dimension d with random rotations and translations up to `spread` from the origin.
Eigen::MatrixXd random_poses(int d, int n, double spread, std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd X(d, (d + 1) * n);
  for (int i = 0; i < n; ++i) {
    Eigen::MatrixXd A(d, d);
    for (int a = 0; a < d; ++a)
      for (int b = 0; b < d; ++b) A(a, b) = g(rng);
    Eigen::MatrixXd R = polar_factor(A);
    if (R.determinant() < 0) R.col(0) *= -1;
    X.middleCols((d + 1) * i, d) = R;
    for (int a = 0; a < d; ++a) X(a, (d + 1) * i + d) = spread * g(rng);
  }
  return X;
}

Eigen::MatrixXd skew_of(const Eigen::VectorXd& w) {
  if (w.size() == 1) return Eigen::Matrix2d{{0, -w(0)}, {w(0), 0}};
  return Eigen::Matrix3d{{0, -w(2), w(1)}, {w(2), 0, -w(0)}, {-w(1), w(0), 0}};
}

// Largest change of any relative pose R_i^T R_j, R_i^T (t_j - t_i) between X and Y.
double relative_pose_change(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Y, int d) {
  const Eigen::Index n = X.cols() / (d + 1);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      auto rel = [&](const Eigen::MatrixXd& Z) {
        const Eigen::MatrixXd Ri = Z.middleCols(i * (d + 1), d);
        Eigen::MatrixXd T(d, d + 1);
        T.leftCols(d) = Ri.transpose() * Z.middleCols(j * (d + 1), d);
        T.col(d) = Ri.transpose() * (Z.col(j * (d + 1) + d) - Z.col(i * (d + 1) + d));
        return T;
      };
      worst = std::max(worst, (rel(X) - rel(Y)).cwiseAbs().maxCoeff());
    }
  return worst;
}

TEST(RigidRetraction, ASharedTwistMovesEveryPoseRigidlyWhereThePolarRetractionStretches) {
  std::mt19937 rng(7);
  for (int d : {2, 3}) {
    const int n = 30;
    const LiftedManifold M(d, d, static_cast<std::size_t>(n));
    const Eigen::MatrixXd X = random_poses(d, n, 300.0, rng);  // poses hundreds of metres out
    // Every pose turns by 0.3 rad about the same point p: s_R = W R, s_t = W (t - p).
    Eigen::VectorXd axis = Eigen::VectorXd::Ones(d == 2 ? 1 : 3).normalized();
    const Eigen::MatrixXd W = skew_of(0.3 * axis);
    const Eigen::VectorXd p = Eigen::VectorXd::Constant(d, 120.0);
    Eigen::MatrixXd s(X.rows(), X.cols());
    for (int i = 0; i < n; ++i) {
      s.middleCols((d + 1) * i, d) = W * X.middleCols((d + 1) * i, d);
      s.col((d + 1) * i + d) = W * (X.col((d + 1) * i + d) - p);
    }
    const Eigen::MatrixXd Y = retract_rigid(M, d, X, s);
    EXPECT_LT(M.distance_from_manifold(Y), 1e-12) << "d = " << d;
    EXPECT_LT(relative_pose_change(X, Y, d), 1e-10) << "d = " << d;
    // The point p stays where it is (turning about p): pose 0 is carried about it exactly.
    const Eigen::MatrixXd Q = Y.leftCols(d) * X.leftCols(d).transpose();
    EXPECT_LT((Y.col(d) - (Q * (X.col(d) - p) + p)).norm(), 1e-9) << "d = " << d;
    // The polar retraction with the additive translation stretches the same move by metres.
    EXPECT_GT(relative_pose_change(X, M.retract(X, s), d), 1.0) << "d = " << d;
  }
}

TEST(RigidRetraction, FollowsASmallStepToFirstOrder) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int d : {2, 3}) {
    const int n = 10;
    const LiftedManifold M(d, d, static_cast<std::size_t>(n));
    const Eigen::MatrixXd X = random_poses(d, n, 50.0, rng);
    Eigen::MatrixXd V(X.rows(), X.cols());
    for (Eigen::Index k = 0; k < V.size(); ++k) V.data()[k] = g(rng);
    const Eigen::MatrixXd s = M.tangent_project(X, V);
    double previous = 0.0;
    for (double eps : {1e-2, 1e-3, 1e-4}) {
      const double err = (retract_rigid(M, d, X, eps * s) - X - eps * s).norm();
      EXPECT_LT(err, 100 * eps * eps * s.squaredNorm() + 1e-12) << "d = " << d;
      if (previous > 0) {
        EXPECT_LT(err, 0.02 * previous) << "d = " << d;  // ~eps^2: 100x a decade
      }
      previous = err;
    }
  }
}

TEST(RigidRetraction, ARankLiftedPointUsesThePolarRetraction) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  const int d = 3, r = 5, n = 8;
  const LiftedManifold M(r, d, n);
  Eigen::MatrixXd A(r, (d + 1) * n);
  for (Eigen::Index k = 0; k < A.size(); ++k) A.data()[k] = g(rng);
  const Eigen::MatrixXd X = M.project(A);
  Eigen::MatrixXd V(r, (d + 1) * n);
  for (Eigen::Index k = 0; k < V.size(); ++k) V.data()[k] = g(rng);
  const Eigen::MatrixXd s = 0.1 * M.tangent_project(X, V);
  EXPECT_EQ(retract_rigid(M, d, X, s), M.retract(X, s));
}

}  // namespace
}  // namespace tessera
