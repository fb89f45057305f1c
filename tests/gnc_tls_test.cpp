// GNC-TLS outlier rejection: the weight update, its defaults, and the centralized robust
// solve on small generated graphs with known outliers.
#include <gtest/gtest.h>

#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "test_support.hpp"

namespace tessera {
namespace {

GeneratorResult grid_with_outliers(double fraction, OutlierKind kind = OutlierKind::kRandom) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 125;
  o.num_robots = 5;
  o.seed = 3;
  o.outlier_fraction = fraction;
  o.outlier_kind = kind;
  return generate_pose_graph(o);
}

GncCentralizedOptions gnc_options() {
  GncCentralizedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  return o;
}

TEST(TlsWeights, ChiSquareQuantileMatchesTables) {
  EXPECT_NEAR(chi_square_quantile(0.99, 6), 16.8119, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.95, 3), 7.8147, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.9999, 3), 21.1075, 1e-3);
  RobustOptions o;  // default: 1 - 1e-4 / m, so the bound grows slowly with the graph
  EXPECT_DOUBLE_EQ(tls_threshold_squared(o, 3, 100), chi_square_quantile(1 - 1e-6, 6));
  EXPECT_DOUBLE_EQ(tls_threshold_squared(o, 2, 10000), chi_square_quantile(1 - 1e-8, 3));
  EXPECT_NEAR(chi_square_quantile(1 - 1e-8, 3), 40.1300, 1e-3);
  EXPECT_GT(tls_threshold_squared(o, 3, 20000), tls_threshold_squared(o, 3, 100));
  o.inlier_quantile = 0.99;
  EXPECT_DOUBLE_EQ(tls_threshold_squared(o, 3, 20000), chi_square_quantile(0.99, 6));
  o.inlier_threshold = 3;
  EXPECT_DOUBLE_EQ(tls_threshold_squared(o, 2, 100), 9.0);
}

TEST(TlsWeights, WeightIsOneInsideZeroOutsideAndContinuousBetween) {
  const double c2 = 10, mu = 2;
  EXPECT_EQ(tls_weight(0.0, c2, mu), 1.0);
  EXPECT_EQ(tls_weight(1e6, c2, mu), 0.0);
  const double lo = mu / (mu + 1) * c2, hi = (mu + 1) / mu * c2;
  EXPECT_NEAR(tls_weight(lo * (1 + 1e-12), c2, mu), 1.0, 1e-9);
  EXPECT_NEAR(tls_weight(hi * (1 - 1e-12), c2, mu), 0.0, 1e-9);
  double previous = 1.0;
  for (double r2 = lo; r2 <= hi; r2 += (hi - lo) / 50) {
    const double w = tls_weight(r2, c2, mu);
    EXPECT_LE(w, previous + 1e-15);
    previous = w;
  }
  EXPECT_EQ(gnc_initial_mu(4.0, 10.0), 0.0);  // every residual inside: nothing to do
  EXPECT_NEAR(gnc_initial_mu(10.0, 10.0), 1.0, 1e-15);
}

TEST(TlsWeights, OnlyConsecutivePosesAreKnownOdometryInliers) {
  Measurement m;
  m.i = 4;
  m.j = 5;
  EXPECT_TRUE(is_known_inlier(m, KnownInliers::kOdometry));
  EXPECT_FALSE(is_known_inlier(m, KnownInliers::kNone));
  m.j = 7;
  EXPECT_FALSE(is_known_inlier(m, KnownInliers::kOdometry));
}

TEST(RobustOptions, BadOptionsNameTheField) {
  RobustOptions o;
  o.mu_step = 1.0;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.mu_step"));
  o = {};
  o.max_outer_iterations = 0;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.max_outer_iterations"));
  o = {};
  o.inlier_threshold = -1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.inlier_threshold"));
  o = {};
  o.inner_max_iterations = -1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.inner_max_iterations"));
  o = {};
  o.inlier_quantile = 1;
  EXPECT_TRUE(test::validation_names(o, "RobustOptions.inlier_quantile"));
  EXPECT_THROW(parse_robust_kind("gnc"), InputError);
  EXPECT_THROW(parse_known_inliers("all"), InputError);
}

TEST(GncCentralized, RejectsExactlyTheRandomOutliersAndReachesTheCleanOptimum) {
  const GeneratorResult clean = grid_with_outliers(0.0);
  const GeneratorResult dirty = grid_with_outliers(0.25);
  ASSERT_FALSE(dirty.outliers.empty());
  const CentralizedResult reference = solve_centralized(clean.graph);
  ASSERT_TRUE(reference.certified.value_or(false));

  const GncCentralizedResult robust = solve_gnc_centralized(dirty.graph, gnc_options());
  EXPECT_EQ(robust.rejected, dirty.outliers);
  EXPECT_GT(robust.outer_iterations, 0);
  EXPECT_NEAR(robust.final_solve.cost, reference.cost, 1e-6 * reference.cost);
  EXPECT_TRUE(robust.final_solve.certified.value_or(false));
  for (std::size_t e : robust.rejected) EXPECT_EQ(robust.weights[e], 0.0);

  // The plain solve of the same file is dragged away: far above f*_clean.
  const CentralizedResult plain = solve_centralized(dirty.graph);
  EXPECT_GT(plain.cost, 10 * reference.cost);
}

TEST(GncCentralized, CappedInnerSolvesRejectTheSameOutliersInFewerIterations) {
  // On a graph whose odometry start is good, capping the weighted solves between two weight
  // updates (inner_max_iterations) finds the same outliers and the same optimum: only the kept
  // set's solve has to be exact.
  const GeneratorResult dirty = grid_with_outliers(0.25);
  const GncCentralizedResult uncapped = solve_gnc_centralized(dirty.graph, gnc_options());
  GncCentralizedOptions cap = gnc_options();
  cap.robust.inner_max_iterations = 3;
  const GncCentralizedResult capped = solve_gnc_centralized(dirty.graph, cap);
  EXPECT_EQ(uncapped.rejected, dirty.outliers);
  EXPECT_EQ(capped.rejected, dirty.outliers);
  EXPECT_NEAR(capped.final_solve.cost, uncapped.final_solve.cost, 1e-6 * uncapped.final_solve.cost);
  EXPECT_TRUE(capped.final_solve.certified.value_or(false));
  EXPECT_LT(capped.inner_iterations, uncapped.inner_iterations);
  EXPECT_LT(capped.cg_iterations, uncapped.cg_iterations);
}

TEST(GncCentralized, CleanGraphLosesNothingAndEndsAtThePlainOptimum) {
  const GeneratorResult clean = grid_with_outliers(0.0);
  const GncCentralizedResult robust = solve_gnc_centralized(clean.graph, gnc_options());
  const CentralizedResult plain = solve_centralized(clean.graph);
  EXPECT_TRUE(robust.rejected.empty());
  EXPECT_NEAR(robust.final_solve.cost, plain.cost, 1e-6 * plain.cost);
  EXPECT_TRUE(robust.final_solve.certified.value_or(false));
}

TEST(GncCentralized, TheStartVoteTakesChordalOnCleanDataAndTheOdometryUnderOutliers) {
  // The chordal guess fits every edge: on clean data it is nearly the optimum (lower TLS cost
  // than the drifting odometry chain), with wrong closures it is distorted (higher).
  const GeneratorResult clean = grid_with_outliers(0.0);
  const GncCentralizedResult on_clean = solve_gnc_centralized(clean.graph, gnc_options());
  EXPECT_FALSE(on_clean.started_from_known_inliers);
  EXPECT_TRUE(on_clean.rejected.empty());

  const GeneratorResult dirty = grid_with_outliers(0.25);
  const GncCentralizedResult on_dirty = solve_gnc_centralized(dirty.graph, gnc_options());
  EXPECT_TRUE(on_dirty.started_from_known_inliers);
  EXPECT_EQ(on_dirty.rejected, dirty.outliers);

  // Without the vote (or from another initialization) the first solve starts where told.
  GncCentralizedOptions no_vote = gnc_options();
  no_vote.known_inlier_start = false;
  EXPECT_FALSE(solve_gnc_centralized(dirty.graph, no_vote).started_from_known_inliers);
  GncCentralizedOptions from_odometry = gnc_options();
  from_odometry.solver.initialization = Initialization::kOdometry;
  EXPECT_FALSE(solve_gnc_centralized(clean.graph, from_odometry).started_from_known_inliers);
}

TEST(TlsRecheck, AtTheCleanOptimumTheVerdictIsExactlyTheWrongClosures) {
  // A set that keeps one wrong closure and cuts one true closure: at the clean optimum TLS's
  // own verdict (r^2 > c^2) drops the first and takes the second back.
  const GeneratorResult clean = grid_with_outliers(0.0);
  const GeneratorResult dirty = grid_with_outliers(0.25);
  ASSERT_GE(dirty.outliers.size(), 2u);
  const std::vector<Pose> optimum = solve_centralized(clean.graph).poses;
  std::vector<bool> known(dirty.graph.num_measurements());
  std::size_t true_closure = dirty.graph.num_measurements();
  for (std::size_t e = 0; e < known.size(); ++e) {
    known[e] = is_known_inlier(dirty.graph.measurements[e], KnownInliers::kOdometry);
    if (!known[e] && e < dirty.outliers.front()) true_closure = e;
  }
  ASSERT_LT(true_closure, dirty.outliers.front());
  std::vector<std::size_t> rejected(dirty.outliers.begin() + 1, dirty.outliers.end());
  rejected.insert(rejected.begin(), true_closure);
  const double c2 = tls_threshold_squared(RobustOptions{}, 3, dirty.outliers.size());
  const TlsRecheck r = tls_recheck(dirty.graph, known, optimum, c2, rejected);
  EXPECT_EQ(r.rejected, dirty.outliers);
  EXPECT_EQ(r.taken_back, 1u);
  EXPECT_EQ(r.dropped, 1u);
  // Known inliers are never judged, however far off.
  std::vector<Pose> bent = optimum;
  bent[1].t.array() += 30.0;
  for (std::size_t e : tls_recheck(dirty.graph, known, bent, c2, r.rejected).rejected)
    EXPECT_FALSE(known[e]);
}

TEST(GncCentralized, KnownOdometryInliersAreNeverRejected) {
  GeneratorResult r = grid_with_outliers(0.1);
  // Corrupt one odometry edge badly: with known odometry inliers it keeps weight 1, without
  // them it is rejected like any wrong measurement.
  Measurement& odometry = r.graph.measurements[10];
  ASSERT_EQ(odometry.j, odometry.i + 1);
  odometry.t.array() += 25.0;
  GncCentralizedOptions o = gnc_options();
  const GncCentralizedResult known = solve_gnc_centralized(r.graph, o);
  for (std::size_t e : known.rejected) {
    const Measurement& m = r.graph.measurements[e];
    EXPECT_NE(m.j, m.i + 1) << "odometry edge " << e << " rejected";
  }
  EXPECT_EQ(known.weights[10], 1.0);
  o.robust.known_inliers = KnownInliers::kNone;
  const GncCentralizedResult unknown = solve_gnc_centralized(r.graph, o);
  EXPECT_EQ(unknown.weights[10], 0.0);
}

TEST(GncCentralized, ContradictionEverywhereEndsWithAClearMessage) {
  // Two poses measured twice, 50 m apart: no consistent subset connects them.
  PoseGraph g;
  g.d = 2;
  g.num_poses = 2;
  g.source = "contradiction";
  Measurement a;
  a.i = 0;
  a.j = 1;
  a.R = Eigen::MatrixXd::Identity(2, 2);
  a.t = Eigen::Vector2d(1, 0);
  a.kappa = 100;
  a.tau = 100;
  Measurement b = a;
  b.t = Eigen::Vector2d(-49, 0);
  g.measurements = {a, b};
  GncCentralizedOptions o = gnc_options();
  o.robust.known_inliers = KnownInliers::kNone;
  const std::string what = test::input_error_of([&] { solve_gnc_centralized(g, o); });
  EXPECT_NE(what.find("contradiction"), std::string::npos) << what;
  EXPECT_NE(what.find("2 of 2 measurements look like outliers"), std::string::npos) << what;
  EXPECT_NE(what.find("unconnected"), std::string::npos) << what;
}

TEST(WeightedGraph, ScalesWeightsAndDropsRejected) {
  const GeneratorResult r = grid_with_outliers(0.1);
  std::vector<double> w(r.graph.num_measurements(), 1.0);
  w[3] = 0.5;
  w[4] = 0.0;
  const PoseGraph weighted = weighted_graph(r.graph, w, r.graph.initial);
  EXPECT_DOUBLE_EQ(weighted.measurements[3].kappa, 0.5 * r.graph.measurements[3].kappa);
  EXPECT_DOUBLE_EQ(weighted.measurements[4].tau, kMinInnerWeight * r.graph.measurements[4].tau);
  const PoseGraph kept = inlier_graph(r.graph, {4, 9}, r.graph.initial);
  ASSERT_EQ(kept.num_measurements(), r.graph.num_measurements() - 2);
  EXPECT_EQ(kept.measurements[4].i, r.graph.measurements[5].i);
  EXPECT_EQ(kept.measurements[8].j, r.graph.measurements[10].j);
}

}  // namespace
}  // namespace tessera
