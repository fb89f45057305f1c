// IRBCD's scalar recurrences and the shared momentum steps.

#include <gtest/gtest.h>

#include <cmath>

#include "distributed/irbcd.hpp"
#include "distributed/momentum.hpp"
#include "distributed/rbcd_plus_plus.hpp"
#include "manifold/lifted_manifold.hpp"
#include "util/input_error.hpp"

namespace tessera {
namespace {

TEST(Irbcd, GammaSolvesItsQuadraticAndIsAtLeastOneOverN) {
  for (double n : {2.0, 5.0, 17.0})
    for (double sigma : {0.0, 1e-3, 0.5})
      for (double a : {1.0 / n, 0.3, 4.0})
        for (double b : {1.0, 2.5}) {
          const double g = irbcd_gamma(n, sigma, a, b);
          const double lhs = g * g - g / n;
          const double rhs = (1 - g * sigma / n) * a * a / (b * b);
          EXPECT_NEAR(lhs, rhs, 1e-12 * std::max(1.0, std::abs(rhs)));
          EXPECT_GE(g, 1.0 / n);
        }
}

TEST(Irbcd, RecurrencesFollowThePaper) {
  IrbcdOptions o;  // sigma 1e-4, a0 = 1/n, b0 = 1
  const double n = 5;
  IrbcdScheme s(o, n);
  EXPECT_DOUBLE_EQ(s.a(), 1.0 / n);
  EXPECT_DOUBLE_EQ(s.b(), 1.0);
  double a = s.a(), b = s.b();
  for (int k = 0; k < 50; ++k) {
    const MomentumCoefficients c = s.coefficients();
    EXPECT_NEAR(c.alpha, (n - c.gamma * o.sigma) / (c.gamma * (n * n - o.sigma)), 1e-15);
    EXPECT_NEAR(c.beta, 1 - c.gamma * o.sigma / n, 1e-15);
    EXPECT_GT(c.alpha, 0);
    EXPECT_LE(c.alpha, 1);
    s.advance();
    b = b / std::sqrt(c.beta);
    a = c.gamma * b;
    EXPECT_NEAR(s.a(), a, 1e-12 * a);
    EXPECT_NEAR(s.b(), b, 1e-12 * b);
  }
  s.restart();
  EXPECT_DOUBLE_EQ(s.a(), 1.0 / n);
  o.reset_on_restart = false;
  IrbcdScheme keep(o, n);
  keep.advance();
  const double a1 = keep.a();
  keep.restart();
  EXPECT_DOUBLE_EQ(keep.a(), a1);
}

TEST(RbcdPlusPlus, NesterovSequence) {
  RbcdPlusPlusScheme s(RbcdPlusPlusOptions{}, 4);
  MomentumCoefficients c = s.coefficients();
  EXPECT_DOUBLE_EQ(c.gamma, 0.25);  // gamma_{-1} = 0
  EXPECT_DOUBLE_EQ(c.alpha, 1.0);
  double prev = c.gamma;
  for (int k = 0; k < 20; ++k) {
    s.advance();
    c = s.coefficients();
    EXPECT_NEAR(c.gamma, (1 + std::sqrt(1 + 64 * prev * prev)) / 8, 1e-14);
    EXPECT_GT(c.gamma, prev);
    prev = c.gamma;
  }
  s.restart();
  EXPECT_DOUBLE_EQ(s.coefficients().gamma, 0.25);
}

TEST(Momentum, StepsLandOnTheManifold) {
  const LiftedManifold M(5, 3, 7);
  Eigen::MatrixXd Y = M.project(Eigen::MatrixXd::Random(5, 28));
  Eigen::MatrixXd V = M.project(Eigen::MatrixXd::Random(5, 28));
  MomentumCoefficients c{0.3, 0.9, 2.5};
  const Eigen::MatrixXd P = extrapolate(M, c, Y, V);
  EXPECT_LT(M.distance_from_manifold(P), 1e-12);
  const Eigen::MatrixXd Vn = momentum_update(M, c, V, P, M.project(Eigen::MatrixXd::Random(5, 28)));
  EXPECT_LT(M.distance_from_manifold(Vn), 1e-12);
  c.alpha = 0;  // no extrapolation: P = Y
  EXPECT_LT((extrapolate(M, c, Y, V) - Y).norm(), 1e-12);
}

// Points near the manifold (the usual case: blends of nearby iterates) take the Newton-Schulz
// path of Proj_M, far ones the eigen-decomposition: both must give the SVD's polar factor.
TEST(Momentum, ProjectionMatchesThePolarFactorNearAndFar) {
  for (int d : {2, 3}) {
    const LiftedManifold M(5, d, 9);
    const Eigen::MatrixXd Y = M.project(Eigen::MatrixXd::Random(5, 9 * (d + 1)));
    for (double offset : {1e-9, 1e-3, 0.1, 3.0}) {
      const Eigen::MatrixXd V = M.project(Y + offset * Eigen::MatrixXd::Random(5, 9 * (d + 1)));
      const MomentumCoefficients c{0.4, 1.0, 0.0};
      const Eigen::MatrixXd P = extrapolate(M, c, Y, V);
      EXPECT_LT(M.distance_from_manifold(P), 1e-13) << d << " " << offset;
      EXPECT_LT((P - M.project(0.4 * V + 0.6 * Y)).norm(), 1e-12) << d << " " << offset;
    }
  }
}

TEST(Irbcd, BadOptionsNameTheField) {
  IrbcdOptions o;
  o.b0 = -1;
  EXPECT_THROW(o.validate(), InputError);
  o = {};
  o.sigma = 100;  // >= n^2 for n = 5
  try {
    IrbcdScheme s(o, 5);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sigma"), std::string::npos);
  }
}

}  // namespace
}  // namespace tessera
