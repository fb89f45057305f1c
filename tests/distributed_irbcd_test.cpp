// IRBCD's scalar recurrences and the shared momentum steps.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tessera/distributed/irbcd.hpp>
#include <tessera/distributed/momentum.hpp>
#include <tessera/distributed/rbcd_plus_plus.hpp>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "test_support.hpp"

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
  IrbcdOptions o;              // sigma 1e-4, b0 = 1
  o.unit_first_gamma = false;  // a0 as given (the default: gamma_0 = 1, see StartsWithUnitGamma)
  o.a0 = 0.0;                  // the paper's a_0 = 1/n
  o.adaptive_sigma = false;
  o.reset_on_restart = true;
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

// The default start: a_0 such that the first gamma is exactly 1 (so V^1 = Y^1), for any n and
// sigma; a reset (reset_on_restart) returns to it. With unit_first_gamma off, a0 is taken as given
// (a0 = 1: the first gamma solves the quadratic with a = b = 1 and exceeds 1).
TEST(Irbcd, StartsWithUnitGamma) {
  IrbcdOptions o;
  EXPECT_TRUE(o.unit_first_gamma);
  EXPECT_FALSE(o.adaptive_sigma);  // the default (docs/irbcd.md section 3)
  for (double n : {2.0, 3.0, 7.0})
    for (double sigma : {1e-4, 1e-2, 0.5}) {
      IrbcdOptions u = o;
      u.sigma = sigma;
      EXPECT_NEAR(IrbcdScheme(u, n).coefficients().gamma, 1.0, 1e-12) << n << " " << sigma;
    }
  o.reset_on_restart = true;
  const double n = 3;
  IrbcdScheme s(o, n);
  const double g0 = s.coefficients().gamma;
  for (int k = 0; k < 30; ++k) s.advance();
  EXPECT_GT(s.coefficients().gamma, g0);
  s.restart();
  EXPECT_EQ(s.coefficients().gamma, g0);
  IrbcdOptions given = o;
  given.unit_first_gamma = false;
  given.a0 = 1.0;
  IrbcdScheme one(given, n);
  EXPECT_DOUBLE_EQ(one.a(), 1.0);
  const double g1 = one.coefficients().gamma;
  EXPECT_DOUBLE_EQ(g1, irbcd_gamma(n, o.sigma, 1.0, 1.0));
  EXPECT_GT(g1, 1.0);
  given.a0 = 0.0;
  EXPECT_NEAR(IrbcdScheme(given, n).coefficients().gamma, (1 + std::sqrt(5.0)) / (2 * n), 1e-4);
}

// Keeping a, b across restarts (the default) relies on gamma staying below its fixed point
// 1/sqrt(sigma): the momentum a restart keeps is bounded, unlike RBCD++'s growing gamma.
TEST(Irbcd, KeptGammaIsBoundedByItsFixedPointAndSurvivesARestart) {
  IrbcdOptions o;
  o.adaptive_sigma = false;
  EXPECT_FALSE(o.reset_on_restart);  // the default
  const double n = 3;
  IrbcdScheme s(o, n);
  double prev = 0;
  for (int k = 0; k < 20000; ++k) {
    const double g = s.coefficients().gamma;
    EXPECT_LE(g, 1.0 / std::sqrt(o.sigma) * (1 + 1e-12));
    EXPECT_GE(g, prev * (1 - 1e-12));  // monotone towards the fixed point (to round-off)
    prev = g;
    s.advance();
  }
  EXPECT_NEAR(prev, 1.0 / std::sqrt(o.sigma), 1e-3);
  const MomentumCoefficients before = s.coefficients();
  s.restart();
  EXPECT_EQ(s.coefficients().gamma, before.gamma);
  o.reset_on_restart = true;
  IrbcdScheme r(o, n);
  const double gamma0 = r.coefficients().gamma;
  for (int k = 0; k < 100; ++k) r.advance();
  r.restart();
  EXPECT_EQ(r.coefficients().gamma, gamma0);
}

// Adaptive sigma (docs/irbcd.md section 3). sigma 1e-2 with n = 2 puts gamma's fixed point
// 1/sqrt(sigma) = 10 within a few dozen rounds.
IrbcdOptions adaptive_options() {
  IrbcdOptions o;
  o.sigma = 1e-2;
  o.adaptive_sigma = true;
  o.sigma_max = 1e-1;
  o.reset_on_restart = true;   // the restart test checks the reset too
  o.unit_first_gamma = false;  // ... to the paper's a_0 = 1/n
  o.a0 = 0.0;
  return o;
}

TEST(IrbcdAdaptiveSigma, DisabledIsTheFixedRecurrenceAndEnabledMatchesItUntilSaturation) {
  const double n = 2;
  IrbcdOptions fixed_o = adaptive_options();
  fixed_o.adaptive_sigma = false;
  IrbcdScheme fixed(fixed_o, n), adaptive(adaptive_options(), n);
  bool shrunk = false;
  for (int k = 0; k < 300; ++k) {
    const MomentumCoefficients f = fixed.coefficients(), a = adaptive.coefficients();
    EXPECT_EQ(fixed.sigma(), 1e-2);  // never moves when disabled
    if (!shrunk) {                   // bit-identical until the first adjustment
      EXPECT_EQ(f.gamma, a.gamma);
      EXPECT_EQ(f.alpha, a.alpha);
      EXPECT_EQ(f.beta, a.beta);
    }
    fixed.advance();
    adaptive.advance();
    if (adaptive.sigma() != 1e-2 && !shrunk) {
      shrunk = true;
      // Shrunk exactly when gamma reached the saturation fraction of 1/sqrt(sigma).
      EXPECT_GE(a.gamma * std::sqrt(1e-2), adaptive_options().sigma_saturation);
      EXPECT_DOUBLE_EQ(adaptive.sigma(), 1e-2 * adaptive_options().sigma_shrink);
    }
  }
  EXPECT_TRUE(shrunk);
  // The fixed scheme's gamma settles at 1/sqrt(sigma); the adaptive one grows past it.
  EXPECT_NEAR(fixed.coefficients().gamma, 10.0, 0.5);
  EXPECT_GT(adaptive.coefficients().gamma, 12.0);
  EXPECT_LT(adaptive.sigma(), 1e-2 * adaptive_options().sigma_shrink);
}

TEST(IrbcdAdaptiveSigma, ShrinksNoFurtherThanSigmaMin) {
  IrbcdOptions o = adaptive_options();
  o.sigma_min = 1e-3;
  IrbcdScheme s(o, 2);
  for (int k = 0; k < 2000; ++k) {
    s.advance();
    EXPECT_GE(s.sigma(), 1e-3);
  }
  EXPECT_DOUBLE_EQ(s.sigma(), 1e-3);
}

TEST(IrbcdAdaptiveSigma, RestartRaisesSigmaToDampTheRejectedMomentum) {
  IrbcdOptions o = adaptive_options();
  o.sigma = 1e-4;
  const double n = 2;
  IrbcdScheme s(o, n);
  for (int k = 0; k < 40; ++k) s.advance();
  const double gamma_r = s.a() / s.b();                      // the gamma of the round just taken
  ASSERT_LT(gamma_r * std::sqrt(1e-4), o.sigma_saturation);  // no shrink happened
  s.restart();
  const double expected = 1.0 / std::pow(o.sigma_restart_theta * gamma_r, 2);
  EXPECT_GT(expected, 1e-4);
  EXPECT_DOUBLE_EQ(s.sigma(), std::min(expected, o.sigma_max));
  EXPECT_DOUBLE_EQ(s.a(), 1.0 / n);  // a, b reset as before
  EXPECT_DOUBLE_EQ(s.b(), 1.0);
  // Clamped to sigma_max: a restart right after the reset (gamma ~ 1.6 / n) asks for ~1.
  s.restart();
  EXPECT_DOUBLE_EQ(s.sigma(), o.sigma_max);
  // Disabled: a restart leaves sigma alone.
  o.adaptive_sigma = false;
  IrbcdScheme off(o, n);
  for (int k = 0; k < 40; ++k) off.advance();
  off.restart();
  EXPECT_EQ(off.sigma(), 1e-4);
}

TEST(IrbcdAdaptiveSigma, SaveLoadRoundTripKeepsSigma) {
  const double n = 2;
  IrbcdScheme s(adaptive_options(), n);
  for (int k = 0; k < 120; ++k) s.advance();
  ASSERT_NE(s.sigma(), 1e-2);
  const std::vector<double> saved = s.save();
  ASSERT_EQ(saved.size(), 3u);
  IrbcdScheme t(adaptive_options(), n);
  t.load(saved);
  EXPECT_EQ(t.sigma(), s.sigma());
  for (int k = 0; k < 100; ++k) {
    const MomentumCoefficients a = s.coefficients(), b = t.coefficients();
    EXPECT_EQ(a.gamma, b.gamma);
    EXPECT_EQ(a.alpha, b.alpha);
    EXPECT_EQ(a.beta, b.beta);
    s.advance();
    t.advance();
    EXPECT_EQ(s.sigma(), t.sigma());
  }
  // A two-value state (before adaptive sigma) takes the option's sigma; other sizes fail.
  t.load({0.5, 1.0});
  EXPECT_EQ(t.sigma(), 1e-2);
  EXPECT_THROW(t.load({1.0}), std::runtime_error);
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

// Points within ~1e-4 of the manifold (||A^T A - I||; almost every pose of a round) take the
// binomial series for (A^T A)^{-1/2}, nearer ones (below 1e-9) its first term, the others
// Newton-Schulz: each must give the SVD's polar factor to round-off, for both dimensions and for
// the lifted rank as well as r = d (the SVD itself is exact to ~1e-15 here).
TEST(Momentum, ProjectionNearTheManifoldMatchesThePolarFactorToRoundOff) {
  for (int d : {2, 3})
    for (int r : {d, 5}) {
      const int n = 12, w = d + 1;
      const LiftedManifold M(r, d, n);
      std::srand(11);
      const Eigen::MatrixXd Y = M.project(Eigen::MatrixXd::Random(r, n * w));
      for (double t : {1e-10, 3e-9, 1e-7, 1e-6, 1e-5, 3e-5, 1e-4, 1e-3}) {
        const Eigen::MatrixXd A = Y + t * Eigen::MatrixXd::Random(r, n * w);
        const Eigen::MatrixXd P = project_to_manifold(M, A);
        double worst = 0.0;
        for (int i = 0; i < n; ++i) {
          const Eigen::MatrixXd polar = polar_factor(A.middleCols(i * w, d));
          worst = std::max(worst, (P.middleCols(i * w, d) - polar).cwiseAbs().maxCoeff());
          EXPECT_TRUE(P.col(i * w + d) == A.col(i * w + d));  // translations untouched
        }
        EXPECT_LT(worst, 2e-15) << d << " " << r << " " << t;
      }
    }
}

// The round protocol forms P, V (and the neighbours' copies) in place in the agent's buffers:
// writing into an existing matrix, or into one of the inputs, must give exactly what the
// returning forms give, for every rank (the Gram entries of Proj_M are summed in an order that
// depends on r) and for rank-deficient rows (the zero rows of a lifted start).
TEST(Momentum, InPlaceFormsAreBitIdenticalToTheReturningForms) {
  for (int d : {2, 3})
    for (int r : {d, 4, 5, 7, 9}) {
      const LiftedManifold M(r, d, 6);
      const Eigen::MatrixXd Y = M.project(Eigen::MatrixXd::Random(r, 6 * (d + 1)));
      const Eigen::MatrixXd V = M.project(Y + 0.05 * Eigen::MatrixXd::Random(r, 6 * (d + 1)));
      const Eigen::MatrixXd Yn = M.project(Y + 0.05 * Eigen::MatrixXd::Random(r, 6 * (d + 1)));
      const MomentumCoefficients c{0.4, 0.93, 1.7};
      const Eigen::MatrixXd P = extrapolate(M, c, Y, V);
      Eigen::MatrixXd P2 = Eigen::MatrixXd::Constant(r, 6 * (d + 1), 7.0);  // old contents
      extrapolate_into(M, c, Y, V, P2);
      EXPECT_TRUE(P2 == P) << d << " " << r;
      const Eigen::MatrixXd Vn = momentum_update(M, c, V, P, Yn);
      Eigen::MatrixXd V2 = V;
      momentum_update_into(M, c, V2, P, Yn, V2);  // out aliases V, as in the protocol
      EXPECT_TRUE(V2 == Vn) << d << " " << r;
      EXPECT_LT(M.distance_from_manifold(V2), 1e-12);
      Eigen::MatrixXd wrong(r, 3);
      EXPECT_THROW(extrapolate_into(M, c, Y, wrong, P2), std::invalid_argument);
    }
}

// A lifted start keeps r - d zero rows in P and V, and Proj_M then skips them. A pose whose zero
// rows hold a negligible 1e-300 instead takes the full path; every Gram entry and so every
// active row come out the same to the last bit, and the zero rows stay exactly zero.
TEST(Momentum, ProjectionSkippingZeroRowsMatchesTheFullOneBitForBit) {
  for (int d : {2, 3}) {
    const int n = 8, w = d + 1;
    const LiftedManifold Md(d, d, n), M(5, d, n);
    Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(5, n * w), V = Y;
    Y.topRows(d) = Md.project(Eigen::MatrixXd::Random(d, n * w));
    V.topRows(d) = Md.project(Y.topRows(d) + 0.05 * Eigen::MatrixXd::Random(d, n * w));
    const MomentumCoefficients c{0.4, 0.93, 1.7};
    const Eigen::MatrixXd P = extrapolate(M, c, Y, V);
    EXPECT_TRUE(P.bottomRows(5 - d).isZero(0.0)) << d;
    Eigen::MatrixXd Y_full = Y;
    for (int i = 0; i < n; ++i) Y_full(4, i * w) = 1e-300;  // every pose on the full path
    const Eigen::MatrixXd P_full = extrapolate(M, c, Y_full, V);
    EXPECT_FALSE(P_full.bottomRows(1).isZero(0.0)) << d;
    EXPECT_TRUE(P.topRows(d) == P_full.topRows(d)) << d;
    const Eigen::MatrixXd V1 = momentum_update(M, c, V, P, Y);
    const Eigen::MatrixXd V1_full = momentum_update(M, c, V, P, Y_full);
    EXPECT_TRUE(V1.bottomRows(5 - d).isZero(0.0)) << d;
    EXPECT_TRUE(V1.topRows(d) == V1_full.topRows(d)) << d;
    EXPECT_LT(M.distance_from_manifold(V1), 1e-12) << d;
  }
}

TEST(Irbcd, BadOptionsNameTheField) {
  IrbcdOptions o;
  o.b0 = -1;
  EXPECT_THROW(o.validate(), InputError);
  o = {};
  o.sigma = 100;  // >= n^2 for n = 5
  EXPECT_NE(test::input_error_of([&] { IrbcdScheme s(o, 5); }).find("sigma"), std::string::npos);
  const auto names = [](const IrbcdOptions& bad, const char* field) {
    EXPECT_TRUE(test::validation_names(bad, field)) << field;
  };
  IrbcdOptions bad;
  bad.sigma_shrink = 0;
  names(bad, "sigma_shrink");
  bad = {};
  bad.sigma_saturation = 1.5;
  names(bad, "sigma_saturation");
  bad = {};
  bad.sigma_restart_theta = -1;
  names(bad, "sigma_restart_theta");
  bad = {};
  bad.sigma_min = -1;
  names(bad, "sigma_min");
  bad = {};
  bad.sigma_max = 1e-9;  // below sigma_min
  names(bad, "sigma_max");
  bad = {};
  bad.class_score = static_cast<ClassScore>(7);  // not an enumerator
  names(bad, "class_score");
}

}  // namespace
}  // namespace tessera
