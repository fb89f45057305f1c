// `tessera generate --outliers`: wrong loop closures with ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "test_support.hpp"

namespace tessera {
namespace {

GeneratorOptions small_grid(double outliers, OutlierKind kind, std::size_t robots = 5) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 200;
  o.num_robots = robots;
  o.seed = 7;
  o.outlier_fraction = outliers;
  o.outlier_kind = kind;
  return o;
}

bool same_measurement(const Measurement& a, const Measurement& b) {
  return a.i == b.i && a.j == b.j && a.R == b.R && a.t == b.t && a.kappa == b.kappa &&
         a.tau == b.tau;
}

TEST(GenerateOutliers, AppendsTheFractionOfLoopClosuresAfterTheUnchangedCleanGraph) {
  const GeneratorResult clean = generate_pose_graph(small_grid(0.0, OutlierKind::kRandom));
  for (OutlierKind kind : {OutlierKind::kRandom, OutlierKind::kGroup, OutlierKind::kInterRobot}) {
    const GeneratorResult dirty = generate_pose_graph(small_grid(0.25, kind));
    const std::size_t m = clean.graph.num_measurements();
    const auto expected =
        static_cast<std::size_t>(std::llround(0.25 * static_cast<double>(clean.loop_closures())));
    ASSERT_EQ(dirty.outliers.size(), expected) << outlier_kind_name(kind);
    ASSERT_EQ(dirty.graph.num_measurements(), m + expected);
    for (std::size_t e = 0; e < m; ++e)
      ASSERT_TRUE(same_measurement(clean.graph.measurements[e], dirty.graph.measurements[e]));
    for (std::size_t k = 0; k < expected; ++k) EXPECT_EQ(dirty.outliers[k], m + k);
    EXPECT_TRUE(clean.outliers.empty());
  }
}

TEST(GenerateOutliers, SameSeedGivesTheSameOutliers) {
  const GeneratorResult a = generate_pose_graph(small_grid(0.5, OutlierKind::kGroup));
  const GeneratorResult b = generate_pose_graph(small_grid(0.5, OutlierKind::kGroup));
  ASSERT_EQ(a.graph.num_measurements(), b.graph.num_measurements());
  for (std::size_t e = 0; e < a.graph.num_measurements(); ++e)
    EXPECT_TRUE(same_measurement(a.graph.measurements[e], b.graph.measurements[e]));
}

TEST(GenerateOutliers, OutliersAreFarFromTheTruthAndNeverBetweenConsecutivePoses) {
  for (OutlierKind kind : {OutlierKind::kRandom, OutlierKind::kGroup, OutlierKind::kInterRobot}) {
    const GeneratorResult r = generate_pose_graph(small_grid(0.25, kind));
    for (std::size_t e : r.outliers) {
      const Measurement& m = r.graph.measurements[e];
      EXPECT_GT(m.j, m.i + 1);
      const Pose &a = r.ground_truth[m.i], &b = r.ground_truth[m.j];
      const double r2 =
          m.kappa * (b.R - a.R * m.R).squaredNorm() + m.tau * (b.t - a.t - a.R * m.t).squaredNorm();
      EXPECT_GT(r2, 1000.0) << outlier_kind_name(kind) << " edge " << e;
      if (kind == OutlierKind::kInterRobot) {
        EXPECT_NE(r.robot_of[m.i], r.robot_of[m.j]);
      }
    }
  }
}

TEST(GenerateOutliers, GroupOutliersAgreeWithEachOther) {
  const GeneratorResult r = generate_pose_graph(small_grid(0.25, OutlierKind::kGroup));
  ASSERT_GE(r.outliers.size(), 2u);
  // The first two of a group are (a, b) and (a+1, b+1) with one wrong motion M behind both:
  // x_a * z_ab * (x_{a+1} * z_{a+1,b+1})^{-1} = x_b x_{b+1}^{-1} up to noise.
  const Measurement& m0 = r.graph.measurements[r.outliers[0]];
  const Measurement& m1 = r.graph.measurements[r.outliers[1]];
  ASSERT_EQ(m1.i, m0.i + 1);
  ASSERT_EQ(m1.j, m0.j + 1);
  const auto& x = r.ground_truth;
  const Eigen::MatrixXd Rb0 = x[m0.i].R * m0.R, Rb1 = x[m1.i].R * m1.R;  // moved R_b, R_{b+1}
  const Eigen::MatrixXd relative_measured = Rb0.transpose() * Rb1;
  const Eigen::MatrixXd relative_true = x[m0.j].R.transpose() * x[m1.j].R;
  EXPECT_LT((relative_measured - relative_true).norm(), 0.1);
}

TEST(GenerateOutliers, BadOutlierOptionsNameTheField) {
  using test::validation_names;
  EXPECT_TRUE(validation_names(small_grid(0.95, OutlierKind::kRandom), "outlier_fraction"));
  EXPECT_TRUE(validation_names(small_grid(-0.1, OutlierKind::kRandom), "outlier_fraction"));
  EXPECT_TRUE(validation_names(small_grid(0.1, OutlierKind::kInterRobot, 1), "outlier_kind"));
  EXPECT_THROW(parse_outlier_kind("groups"), InputError);
  EXPECT_EQ(parse_outlier_kind("inter-robot"), OutlierKind::kInterRobot);
}

}  // namespace
}  // namespace tessera
