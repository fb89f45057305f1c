// Trajectory accuracy (tessera eval): Umeyama alignment recovers a known motion exactly, ATE
// and RPE match hand computations, poses match by stamp within the tolerance or by index,
// and TUM / graph / folder inputs read as trajectories.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <string>
#include <tessera/eval/alignment.hpp>
#include <tessera/eval/trajectory_error.hpp>
#include <tessera/io/trajectory_reader.hpp>
#include <tessera/util/input_error.hpp>

#include "test_support.hpp"

namespace {

using namespace tessera;
using tessera::test::temp_dir;
using tessera::test::write_file;

// A 3D robot trajectory of n poses along a twisted curve, stamped 0.1 s apart.
RobotTrajectory curve(const std::string& name, int n) {
  RobotTrajectory r;
  r.name = name;
  r.has_stamps = true;
  for (int k = 0; k < n; ++k) {
    TrajectoryPose p;
    p.index = static_cast<std::uint64_t>(k);
    p.stamp = 0.1 * k;
    p.t << std::cos(0.3 * k) * 4, std::sin(0.3 * k) * 3, 0.2 * k;
    p.R = Eigen::AngleAxisd(0.3 * k, Eigen::Vector3d(0.2, 0.1, 1).normalized()).toRotationMatrix();
    r.poses.push_back(p);
  }
  return r;
}

Trajectory team(std::vector<RobotTrajectory> robots) {
  Trajectory t;
  t.d = 3;
  t.source = "mem";
  t.robots = std::move(robots);
  return t;
}

// Every pose moved by x -> s Q x + c (and rotations by Q).
Trajectory moved(const Trajectory& t, const Eigen::Matrix3d& Q, const Eigen::Vector3d& c,
                 double s = 1) {
  Trajectory out = t;
  for (auto& r : out.robots)
    for (auto& p : r.poses) {
      p.t = s * Q * p.t + c;
      p.R = Q * p.R;
    }
  return out;
}

TEST(Alignment, UmeyamaRecoversAKnownRotationAndTranslationExactly) {
  const Trajectory truth = team({curve("a", 20)});
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d c(5, -3, 2);
  // The estimate is the truth moved by (Q, c): alignment must give back (Q^T, -Q^T c).
  const Trajectory est = moved(truth, Q, c);
  const auto r = trajectory_error(est, truth);
  EXPECT_NEAR((r.alignment.R - Q.transpose()).norm(), 0, 1e-12);
  EXPECT_NEAR((r.alignment.t - (-Q.transpose() * c)).norm(), 0, 1e-12);
  EXPECT_NEAR(r.ate.max, 0, 1e-12);
  EXPECT_NEAR(r.rpe.max, 0, 1e-12);
  // sim3 also recovers a scale of 2.5.
  TrajectoryErrorOptions sim;
  sim.align = AlignMode::kSim3;
  const auto s = trajectory_error(moved(truth, Q, c, 2.5), truth, sim);
  EXPECT_NEAR(s.alignment.scale, 1 / 2.5, 1e-12);
  EXPECT_NEAR(s.ate.max, 0, 1e-12);
}

TEST(Alignment, PlanarTrajectoriesAlignInSe2) {
  Eigen::MatrixXd from(2, 4), to(2, 4);
  from << 0, 1, 1, 0, 0, 0, 2, 2;
  const double a = 0.7;
  Eigen::Matrix2d Q;
  Q << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  to = (Q * from).colwise() + Eigen::Vector2d(1, 2);
  const Alignment al = umeyama_alignment(from, to, AlignMode::kSe3);
  EXPECT_EQ(al.R.rows(), 2);
  EXPECT_NEAR((al.R - Q).norm(), 0, 1e-12);
  EXPECT_NEAR((al.t - Eigen::Vector2d(1, 2)).norm(), 0, 1e-12);
}

TEST(TrajectoryError, AteAndRpeMatchAHandComputation) {
  // Truth: 4 poses on the x axis, identity rotations. Estimate: the same with position
  // errors 0, 3, 0, 4 along y. No alignment, so the ATE is exactly those errors.
  RobotTrajectory g, e;
  g.name = e.name = "a";
  const double dy[] = {0, 3, 0, 4};
  for (int k = 0; k < 4; ++k) {
    TrajectoryPose p;
    p.index = static_cast<std::uint64_t>(k);
    p.t << k, 0, 0;
    g.poses.push_back(p);
    p.t << k, dy[k], 0;
    e.poses.push_back(p);
  }
  TrajectoryErrorOptions none;
  none.align = AlignMode::kNone;
  const auto r = trajectory_error(team({e}), team({g}), none);
  EXPECT_EQ(r.matched_by, "index");
  // ATE: errors {0, 3, 0, 4}: rmse sqrt(25/4) = 2.5, mean 7/4, median (0+3)/2, max 4.
  EXPECT_DOUBLE_EQ(r.ate.rmse, 2.5);
  EXPECT_DOUBLE_EQ(r.ate.mean, 1.75);
  EXPECT_DOUBLE_EQ(r.ate.median, 1.5);
  EXPECT_DOUBLE_EQ(r.ate.max, 4);
  // RPE, delta 1: motion errors |dy[k+1] - dy[k]| = 3, 3, 4: rmse sqrt(34/3).
  EXPECT_DOUBLE_EQ(r.rpe.max, 4);
  EXPECT_NEAR(r.rpe.rmse, std::sqrt(34.0 / 3), 1e-15);
  EXPECT_DOUBLE_EQ(r.rpe.median, 3);
  // delta 2: |0 - 0| = 0 and |4 - 3| = 1.
  none.delta = 2;
  const auto r2 = trajectory_error(team({e}), team({g}), none);
  EXPECT_EQ(r2.rpe.count, 2u);
  EXPECT_DOUBLE_EQ(r2.rpe.mean, 0.5);
}

TEST(TrajectoryError, RpeIsMeasuredInThePoseFrame) {
  // Truth turns by 90 degrees at pose 1; the estimate drifts 1 m sideways in pose 1's frame
  // between poses 1 and 2. The RPE of that step is 1 whatever the heading.
  RobotTrajectory g, e;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  TrajectoryPose p0, p1, p2;
  p1.index = 1;
  p2.index = 2;
  p1.t << 1, 0, 0;
  p1.R = turn;
  p2.R = turn;
  p2.t << 1, 1, 0;  // one metre forward in pose 1's frame (its x axis is the world's y)
  g.poses = {p0, p1, p2};
  p2.t << 0, 1, 0;  // ... and one metre to the left of that
  e.poses = {p0, p1, p2};
  TrajectoryErrorOptions none;
  none.align = AlignMode::kNone;
  const auto r = trajectory_error(team({e}), team({g}), none);
  EXPECT_NEAR(r.rpe.max, 1, 1e-15);
  EXPECT_NEAR(r.robots[0].rpe.mean, 0.5, 1e-15);
}

TEST(TrajectoryError, MatchesByStampWithinTheToleranceAndPerRobot) {
  Trajectory truth = team({curve("a", 10), curve("b", 10)});
  Trajectory est = truth;
  for (auto& p : est.robots[1].poses) p.stamp += 0.004;  // clock offset under the tolerance
  est.robots[0].poses.erase(est.robots[0].poses.begin() + 3);
  const auto r = trajectory_error(est, truth);
  EXPECT_EQ(r.matched_by, "stamp");
  EXPECT_EQ(r.matched, 19u);
  ASSERT_EQ(r.robots.size(), 2u);
  EXPECT_EQ(r.robots[0].name, "a");
  EXPECT_EQ(r.robots[0].matched, 9u);
  TrajectoryErrorOptions tight;
  tight.stamp_tolerance = 0.001;
  EXPECT_EQ(trajectory_error(est, truth, tight).matched, 9u);  // robot b no longer matches
  Trajectory other = truth;
  other.robots[1].name = "c";
  EXPECT_THROW(trajectory_error(truth, other), InputError);  // robot b missing
}

TEST(TrajectoryError, OptionsNameTheBadField) {
  TrajectoryErrorOptions o;
  o.delta = 0;
  EXPECT_TRUE(tessera::test::validation_names(o, "delta"));
  o = {};
  o.stamp_tolerance = -1;
  EXPECT_TRUE(tessera::test::validation_names(o, "stamp_tolerance"));
}

TEST(TrajectoryReader, TumFilesFoldersAndGraphs) {
  const std::string dir = temp_dir();
  const std::string tum = write_file(dir, "t.tum",
                                     "# timestamp tx ty tz qx qy qz qw\n"
                                     "1.5 1 2 0 0 0 0 1\n2.5 2 2 0 0 0 0.7071067811865476 "
                                     "0.7071067811865476\n");
  const Trajectory t = read_tum_trajectory(tum);
  EXPECT_EQ(t.d, 2);
  ASSERT_EQ(t.robots[0].poses.size(), 2u);
  EXPECT_TRUE(t.robots[0].has_stamps);
  EXPECT_DOUBLE_EQ(t.robots[0].poses[1].stamp, 2.5);
  EXPECT_NEAR(t.robots[0].poses[1].R(1, 0), 1, 1e-12);
  std::filesystem::create_directories(dir + "/robots");
  write_file(dir + "/robots", "robot_a.tum",
             "# timestamp = pose index (no stamps given)\n0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n");
  write_file(dir + "/robots", "robot_b.tum", "7 0 0 1 0 0 0 1\n");
  const Trajectory f = read_trajectory(dir + "/robots");
  ASSERT_EQ(f.robots.size(), 2u);
  EXPECT_EQ(f.robots[0].name, "a");
  EXPECT_FALSE(f.robots[0].has_stamps);
  EXPECT_EQ(f.robots[0].poses[1].index, 1u);
  EXPECT_EQ(f.d, 3);
  const std::string g = write_file(dir, "g.g2o",
                                   "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n"
                                   "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n");
  const Trajectory gt = read_trajectory(g);
  EXPECT_EQ(gt.d, 2);
  EXPECT_EQ(gt.robots[0].poses[1].index, 1u);
}

TEST(TrajectoryReaderErrors, BadTumLineNamesFileAndLine) {
  const std::string path = write_file(temp_dir(), "bad.tum", "# c\n1 2 3 4 5 6 7 1\n1 2 3\n");
  try {
    read_tum_trajectory(path);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path + ":3: a TUM line has 8 values", 0), 0u) << e.what();
  }
}

}  // namespace
