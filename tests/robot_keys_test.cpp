// Robot-keyed graphs at the I/O boundary: 64-bit GTSAM keys, ids in any order, FIX lines,
// TORO records, timestamps, the input frame of the output, per-robot trajectory files and
// the robot ownership used by the sequential baseline. Bad input names file and line.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <sstream>
#include <string>
#include <tessera/graph/input_frame.hpp>
#include <tessera/graph/robot_summary.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/io/robot_trajectories.hpp>
#include <tessera/io/stamps_reader.hpp>
#include <tessera/io/tum_writer.hpp>
#include <tessera/partition/robot_partition.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "g2o_text.hpp"
#include "test_support.hpp"

namespace {

using namespace tessera;
using tessera::test::expect_g2o_error;
using tessera::test::read_test_g2o;
using tessera::test::temp_dir;
using tessera::test::write_file;

const std::string kInfo2 = " 10 0 0 10 0 5";

std::uint64_t key(char robot, std::uint64_t index) {
  return gtsam_key(robot, index);
}

std::string vertex2(std::uint64_t id, double x, double y, double th) {
  std::ostringstream s;
  s.precision(17);
  s << "VERTEX_SE2 " << id << " " << x << " " << y << " " << th << "\n";
  return s.str();
}
std::string edge2(std::uint64_t i, std::uint64_t j, double dx = 1, double dy = 0, double dth = 0) {
  std::ostringstream s;
  s.precision(17);
  s << "EDGE_SE2 " << i << " " << j << " " << dx << " " << dy << " " << dth << kInfo2 << "\n";
  return s.str();
}

// Two robots a and b, three poses each, written b first and out of order; odometry in each,
// one intra-robot closure (a0-a2) and two inter-robot closures.
std::string two_robot_text() {
  std::string t;
  for (int k : {2, 0, 1}) t += vertex2(key('b', k), k, 5, 0);
  for (int k : {0, 1, 2}) t += vertex2(key('a', k), k, 0, 0);
  t += edge2(key('a', 0), key('a', 1)) + edge2(key('a', 1), key('a', 2));
  t += edge2(key('b', 0), key('b', 1)) + edge2(key('b', 1), key('b', 2));
  t += edge2(key('a', 0), key('a', 2), 2, 0, 0);
  t += edge2(key('a', 0), key('b', 0), 0, 5, 0) + edge2(key('a', 2), key('b', 2), 0, 5, 0);
  return t;
}

TEST(RobotKeys, GtsamKeysAreDetectedAndNumberedByRobotThenIndex) {
  const auto r = read_test_g2o(two_robot_text());
  const PoseGraph& g = r.graph;
  const PoseKeys& keys = r.keys;
  ASSERT_EQ(g.num_poses, 6u);
  EXPECT_EQ(keys.scheme, KeyScheme::kGtsam);
  EXPECT_EQ(keys.robot_names, (std::vector<std::string>{"a", "b"}));
  // 'a' < 'b': robot a's poses come first, each robot in index order.
  for (std::size_t k = 0; k < 6; ++k) {
    EXPECT_EQ(keys.id(k), key(k < 3 ? 'a' : 'b', k % 3));
    EXPECT_EQ(keys.robot_of(k), k < 3 ? 0u : 1u);
    EXPECT_EQ(keys.index_in_robot(k), k % 3);
    EXPECT_DOUBLE_EQ(g.initial[k].t(1), k < 3 ? 0.0 : 5.0);
  }
  EXPECT_EQ(g.measurements[5].i, 0u);  // a0 - b0
  EXPECT_EQ(g.measurements[5].j, 3u);
  EXPECT_NE(r.stats.keys_detected.find("gtsam keys"), std::string::npos);
  EXPECT_NE(r.stats.keys_detected.find("2 robots a, b"), std::string::npos);
}

TEST(RobotKeys, LargestKeyAndPlainChoiceAreAccepted) {
  // 'a' << 56 is 6989586621679009792, the id the reader used to refuse.
  const auto r = read_test_g2o(edge2(6989586621679009792ull, 6989586621679009793ull));
  EXPECT_EQ(r.keys.id(0), 6989586621679009792ull);
  G2oReadOptions plain;
  plain.keys = KeyScheme::kPlain;
  const auto p = read_test_g2o(two_robot_text(), plain);
  EXPECT_EQ(p.keys.num_robots(), 1u);
  EXPECT_EQ(p.keys.scheme, KeyScheme::kPlain);
  // The largest 64-bit id is a valid (plain) id.
  EXPECT_EQ(read_test_g2o(edge2(0, 18446744073709551615ull)).keys.id(1), 18446744073709551615ull);
}

TEST(RobotKeys, LabeledKeysTakeTheRobotFromBits48To55) {
  auto labeled = [](char robot, std::uint64_t k) {
    return std::uint64_t{'x'} << 56 | std::uint64_t(static_cast<unsigned char>(robot)) << 48 | k;
  };
  const auto r = read_test_g2o(edge2(labeled('a', 0), labeled('a', 1)) +
                               edge2(labeled('a', 1), labeled('c', 0)));
  EXPECT_EQ(r.keys.scheme, KeyScheme::kGtsamLabeled);
  EXPECT_EQ(r.keys.robot_names, (std::vector<std::string>{"a", "c"}));
  EXPECT_EQ(r.keys.index_in_robot(1), 1u);
}

TEST(RobotKeysErrors, BadKeyUnderGtsamNamesTheLine) {
  G2oReadOptions gtsam;
  gtsam.keys = KeyScheme::kGtsam;
  expect_g2o_error(edge2(key('a', 0), key('a', 1)) + edge2(key('a', 1), 7),
                   "t.g2o:2: ", "pose id j '7' is not a GTSAM key (--keys gtsam)", gtsam);
  // Without --keys gtsam the same file is plain ids (one robot).
  EXPECT_EQ(
      read_test_g2o(edge2(key('a', 0), key('a', 1)) + edge2(key('a', 1), 7)).keys.num_robots(), 1u);
}

TEST(RobotKeysErrors, DuplicateKeyNamesBothLines) {
  expect_g2o_error(vertex2(key('a', 0), 0, 0, 0) + vertex2(key('b', 0), 0, 0, 0) +
                       vertex2(key('a', 0), 1, 0, 0) + edge2(key('a', 0), key('b', 0)),
                   "t.g2o:3: ", "duplicate VERTEX id 6989586621679009792 (first on line 1)");
}

TEST(RobotKeys, FixChoosesTheAnchorAndTheOutputKeepsItsVertexValue) {
  const std::string text = two_robot_text() + "FIX " + std::to_string(key('b', 1)) + "\n";
  const G2oReadResult r = read_test_g2o(text);
  const PoseGraph& g = r.graph;
  ASSERT_TRUE(r.keys.fixed.has_value());
  EXPECT_EQ(*r.keys.fixed, 4u);
  EXPECT_EQ(anchor_pose(r.keys), 4u);
  // A solution in another gauge: every pose rotated by 30 degrees and shifted.
  const double c = std::cos(0.5236), s = std::sin(0.5236);
  Eigen::MatrixXd Q(2, 2);
  Q << c, -s, s, c;
  std::vector<Pose> poses;
  for (const Pose& p : g.initial) poses.push_back({Q * p.R, Q * p.t + Eigen::Vector2d(3, -1)});
  move_to_input_frame(g, r.keys, poses);
  for (std::size_t k = 0; k < g.num_poses; ++k) {
    EXPECT_NEAR((poses[k].t - g.initial[k].t).norm(), 0, 1e-12) << k;
    EXPECT_NEAR((poses[k].R - g.initial[k].R).norm(), 0, 1e-12) << k;
  }
  EXPECT_EQ(poses[4].t, g.initial[4].t);  // the anchor exactly
}

TEST(RobotKeysErrors, FixOfAnUnknownPoseNamesTheLine) {
  expect_g2o_error(edge2(0, 1) + "FIX 5\n", "t.g2o:2: ", "FIX names pose 5");
}

TEST(RobotKeys, WrittenGraphKeepsTheInputIdsAndFix) {
  const G2oReadResult r =
      read_test_g2o(two_robot_text() + "FIX " + std::to_string(key('a', 0)) + "\n");
  const std::string path = temp_dir() + "/out.g2o";
  write_g2o(r.graph, r.keys, r.graph.initial, path);
  const std::string text = test::read_text_file(path);
  EXPECT_NE(text.find("VERTEX_SE2 " + std::to_string(key('b', 2)) + " "), std::string::npos);
  EXPECT_NE(text.find("FIX " + std::to_string(key('a', 0))), std::string::npos);
  const G2oReadResult back = read_g2o_file(path);
  EXPECT_EQ(back.keys.ids, r.keys.ids);
  EXPECT_EQ(back.keys.robot, r.keys.robot);
  EXPECT_EQ(back.keys.fixed, r.keys.fixed);
  // One TUM file: the key as timestamp, exactly (no double rounding of a 64-bit id).
  write_tum(r.graph.initial, r.keys, path + ".tum");
  EXPECT_EQ(test::read_text_file(path + ".tum")
                .rfind(std::to_string(key('a', 0)) + " 0 0 0 0 0 0 1\n", 0),
            0u);
}

TEST(RobotKeys, SummaryCountsPosesOdometryAndClosuresPerRobot) {
  const G2oReadResult r = read_test_g2o(two_robot_text());
  const RobotSummary s = summarize_robots(r.graph, r.keys);
  ASSERT_EQ(s.robots.size(), 2u);
  EXPECT_EQ(s.robots[0].name, "a");
  EXPECT_EQ(s.robots[0].poses, 3u);
  EXPECT_EQ(s.robots[0].odometry, 2u);
  EXPECT_EQ(s.robots[0].intra_closures, 1u);
  EXPECT_EQ(s.robots[0].inter_closures, 2u);
  EXPECT_EQ(s.robots[1].intra_closures, 0u);
  EXPECT_EQ(s.robots[1].inter_closures, 2u);
  EXPECT_EQ(s.odometry, 4u);
  EXPECT_EQ(s.intra_closures, 1u);
  EXPECT_EQ(s.inter_closures, 2u);
}

TEST(RobotKeys, SequentialBaselineOfAMultiRobotFileIsEachRobotItsPoses) {
  const G2oReadResult r = read_test_g2o(two_robot_text());
  const auto parts = robot_partition(r.keys, 6, 2);
  ASSERT_TRUE(parts.has_value());
  EXPECT_EQ(*parts, (std::vector<int>{0, 0, 0, 1, 1, 1}));
  EXPECT_FALSE(robot_partition(r.keys, 6, 3).has_value());  // not one block per robot
  EXPECT_FALSE(robot_partition(read_test_g2o(edge2(0, 1) + edge2(1, 2)).keys, 3, 2).has_value());
}

TEST(RobotTrajectories, OneTumFilePerRobotWithIndicesOrStamps) {
  G2oReadResult r = read_test_g2o(two_robot_text());
  const PoseGraph& g = r.graph;
  const std::string dir = temp_dir() + "/tum";
  auto files = write_robot_trajectories(g, r.keys, g.initial, dir);
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[1], dir + "/robot_b.tum");
  std::string b = test::read_text_file(files[1]);
  EXPECT_NE(b.find(kTumIndexStampsNote), std::string::npos);
  EXPECT_NE(b.find("\n2 2 5 0 0 0 0 1\n"), std::string::npos) << b;
  r.keys.stamps = {10, 10.5, 11, 20, 20.25, 20.5};
  files = write_robot_trajectories(g, r.keys, g.initial, dir);
  b = test::read_text_file(files[1]);
  EXPECT_NE(b.find("\n20.5 2 5 0 0 0 0 1\n"), std::string::npos) << b;
  EXPECT_EQ(b.find(kTumIndexStampsNote), std::string::npos);
}

TEST(Stamps, ByIdOrByOrder) {
  const G2oReadResult r = read_test_g2o(two_robot_text());
  const std::string dir = temp_dir();
  std::string by_id = "# id stamp\n";
  for (int k = 2; k >= 0; --k)
    by_id += std::to_string(key('b', k)) + " " + std::to_string(20 + k) + "\n";
  for (int k = 0; k < 3; ++k)
    by_id += std::to_string(key('a', k)) + " " + std::to_string(10 + k) + "\n";
  EXPECT_EQ(read_stamps_file(write_file(dir, "s.txt", by_id), r.graph, r.keys),
            (std::vector<double>{10, 11, 12, 20, 21, 22}));
  std::string tum;
  for (int k = 0; k < 6; ++k) tum += std::to_string(100 + k) + ".5 0 0 0 0 0 0 1\n";
  EXPECT_EQ(read_stamps_file(write_file(dir, "s.tum", tum), r.graph, r.keys),
            (std::vector<double>{100.5, 101.5, 102.5, 103.5, 104.5, 105.5}));
}

void expect_stamps_error(const std::string& text, const std::string& where,
                         const std::string& problem) {
  const G2oReadResult r = read_test_g2o(two_robot_text());
  const std::string path = write_file(temp_dir(), "bad.txt", text);
  try {
    read_stamps_file(path, r.graph, r.keys);
    ADD_FAILURE() << "no error for stamps:\n" << text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path + where, 0), 0u) << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << msg;
  }
}

TEST(StampsErrors, MismatchNamesFileAndLine) {
  const std::string a0 = std::to_string(key('a', 0));
  expect_stamps_error("# c\n" + a0 + " 1\n42 2\n", ":3: ", "pose id 42 is not a pose of t.g2o");
  expect_stamps_error(a0 + " 1\n" + a0 + " 2\n", ":2: ", "already has a stamp (line 1)");
  expect_stamps_error(a0 + " 1\n", ": ", "1 stamps for the 6 poses");
  expect_stamps_error(a0 + " x\n", ":1: ", "stamp 'x' is not a finite number");
  std::string tum;
  for (int k = 0; k < 7; ++k) tum += std::to_string(k) + " 0 0 0 0 0 0 1\n";
  expect_stamps_error(tum, ":7: ", "more stamp lines than the 6 poses");
  expect_stamps_error("1 2 3\n", ":1: ", "a stamps line has 2 values");
}

// ---------------------------------------------------------------- TORO

TEST(Toro, TwoDRecordsReadLikeTheirG2oTwin) {
  // TORO's information order is xx xy yy tt xt yt; g2o's is xx xy xt yy yt tt.
  const auto toro =
      read_test_g2o("VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0.1\nEDGE2 0 1 1 0.2 0.1 10 1 20 5 0.5 0.25\n");
  const auto g2o = read_test_g2o(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0.1\nEDGE_SE2 0 1 1 0.2 0.1 10 1 0.5 20 0.25 5\n");
  EXPECT_EQ(toro.stats.format, "toro");
  EXPECT_EQ(g2o.stats.format, "g2o");
  const Measurement &a = toro.graph.measurements[0], &b = g2o.graph.measurements[0];
  EXPECT_DOUBLE_EQ(a.kappa, b.kappa);
  EXPECT_DOUBLE_EQ(a.tau, b.tau);
  EXPECT_DOUBLE_EQ(a.kappa, 5.0);
  EXPECT_EQ(a.R, b.R);
  EXPECT_EQ(a.t, b.t);
}

TEST(Toro, ThreeDRecordsUseRollPitchYawAndScaleTheRotationInformation) {
  // yaw = pi/2 about z; information diag(4, 4, 4, 3, 3, 3) on (x y z roll pitch yaw).
  const std::string info = " 4 0 0 0 0 0 4 0 0 0 0 4 0 0 0 3 0 0 3 0 3";
  const auto r = read_test_g2o(
      "VERTEX3 0 0 0 0 0 0 0\nVERTEX3 1 1 2 3 0 0 1.5707963267948966\n"
      "EDGE3 0 1 1 2 3 0 0 1.5707963267948966" +
      info + "\n");
  const PoseGraph& g = r.graph;
  EXPECT_EQ(g.d, 3);
  Eigen::Matrix3d want;
  want << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_NEAR((g.measurements[0].R - want).norm(), 0, 1e-12);
  EXPECT_NEAR((g.initial[1].R - want).norm(), 0, 1e-12);
  EXPECT_DOUBLE_EQ(g.measurements[0].tau, 4.0);
  // The angle information 3 is 12 on the quaternion's vector part (half angles): kappa =
  // 3 / (2 trace(inv(12 I))) = 6, as the g2o twin "... 12 0 0 12 0 12" gives.
  EXPECT_DOUBLE_EQ(g.measurements[0].kappa, 6.0);
  // roll then pitch then yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
  const auto rp =
      read_test_g2o("EDGE3 0 1 0 0 0 0.3 -0.2 0.1" + info + "\n").graph.measurements[0].R;
  const Eigen::Matrix3d expect = (Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))
                                     .toRotationMatrix();
  EXPECT_NEAR((rp - expect).norm(), 0, 1e-12);
}

TEST(ToroErrors, ShortRowMixedDialectsAndUnknownFormat) {
  expect_g2o_error("VERTEX2 0 0 0 0\nEDGE2 0 1 1 0 0 10 0 10 5 0\n", "t.g2o:2: ",
                   "EDGE2 needs 11 values (i j dx dy dtheta Ixx Ixy Iyy Itt Ixt Iyt), found 10");
  expect_g2o_error("EDGE3 0 1 0 0 0 0 0 0 1\n", "t.g2o:1: ", "EDGE3 needs 29 values");
  expect_g2o_error("VERTEX2 0 0 0 0\nVERTEX_SE2 1 0 0 0\n", "t.g2o:2: ",
                   "mixed g2o and TORO records: VERTEX_SE2 here, but line 1 has VERTEX2");
  expect_g2o_error("0.5 1 2 3 0 0 0 1\n", "t.g2o:1: ", "not a g2o file");
  expect_g2o_error("0.5 1 2 3 0 0 0 1\n", "t.g2o:1: ", "nor a TORO file");
}

}  // namespace
