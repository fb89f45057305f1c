// The dpgo measurement CSV reader: one file or a folder of robot<k>/measurements.csv.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <fstream>
#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/io/dpgo_csv_reader.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "test_support.hpp"

namespace tessera {
namespace {

const char* const kHeader =
    "robot_src,pose_src,robot_dst,pose_dst,qx,qy,qz,qw,tx,ty,tz,kappa,tau,is_known_inlier,weight\n";

GeneratorResult two_robot_grid(double outliers = 0) {
  GeneratorOptions o;
  o.num_poses = 64;
  o.num_robots = 2;
  o.seed = 5;
  o.outlier_fraction = outliers;
  return generate_pose_graph(o);
}

// One CSV row for measurement m, robot r owning ids [r * half, (r + 1) * half).
std::string row(const Measurement& m, std::size_t half, bool known) {
  const Eigen::Quaterniond q(Eigen::Matrix3d(m.R));
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%zu,%zu,%zu,%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,1\n",
                m.i / half, m.i % half, m.j / half, m.j % half, q.x(), q.y(), q.z(), q.w(), m.t(0),
                m.t(1), m.t(2), m.kappa, m.tau, known ? 1 : 0);
  return buf;
}

void write(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

std::string error_of(const std::string& path) {
  try {
    read_dpgo_csv(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DpgoCsvReader, OneFileGivesTheSameGraphWithRobotOffsetsAndKnownInlierFlags) {
  const GeneratorResult g = two_robot_grid();
  const std::string path = test::temp_dir() + "/measurements.csv";
  std::string text = kHeader;
  for (std::size_t e = 0; e < g.graph.num_measurements(); ++e)
    text += row(g.graph.measurements[e], 32, e % 3 == 0);
  write(path, text);
  ASSERT_TRUE(is_dpgo_csv(path));
  const DpgoCsvGraph r = read_dpgo_csv(path);
  ASSERT_EQ(r.graph.num_poses, 64u);
  ASSERT_EQ(r.graph.num_measurements(), g.graph.num_measurements());
  EXPECT_EQ(r.robot_of[31], 0);
  EXPECT_EQ(r.robot_of[32], 1);
  for (std::size_t e = 0; e < r.graph.num_measurements(); ++e) {
    const Measurement &a = r.graph.measurements[e], &b = g.graph.measurements[e];
    EXPECT_EQ(a.i, b.i);
    EXPECT_EQ(a.j, b.j);
    EXPECT_LT((a.R - b.R).norm(), 1e-12);
    EXPECT_LT((a.t - b.t).norm(), 1e-12);
    EXPECT_DOUBLE_EQ(a.kappa, b.kappa);
    EXPECT_EQ(r.known_inlier[e], e % 3 == 0);
  }
}

TEST(DpgoCsvReader, FolderOfRobotFilesKeepsAMeasurementListedByBothRobotsOnce) {
  const GeneratorResult g = two_robot_grid();
  const std::string dir = test::temp_dir() + "/run";
  mkdir(dir.c_str(), 0755);
  std::string files[2] = {kHeader, kHeader};
  std::size_t shared = 0;
  for (const auto& m : g.graph.measurements) {
    const std::size_t ri = m.i / 32, rj = m.j / 32;
    files[ri] += row(m, 32, false);
    if (rj != ri) {
      files[rj] += row(m, 32, false);
      ++shared;
    }
  }
  ASSERT_GT(shared, 0u);
  for (int k = 0; k < 2; ++k) {
    const std::string sub = dir + "/robot" + std::to_string(k);
    mkdir(sub.c_str(), 0755);
    write(sub + "/measurements.csv", files[k]);
  }
  ASSERT_TRUE(is_dpgo_csv(dir));
  const DpgoCsvGraph r = read_dpgo_csv(dir);
  EXPECT_EQ(r.graph.num_measurements(), g.graph.num_measurements());
  EXPECT_EQ(r.duplicates, shared);
}

TEST(DpgoCsvReader, BadRowsNameFileLineAndField) {
  const std::string dir = test::temp_dir();
  const std::string good = "0,0,0,1,0,0,0,1,1,0,0,100,100,1,1\n";
  const struct {
    std::string body, expected;
  } cases[] = {
      {good + "0,1,0,2,0,0,0,1,1,0,0,100,100,1\n", ":3: expected 15 comma-separated fields"},
      {good + "0,1,0,2,0,0,0,1,1,0,zero,100,100,1,1\n", ":3: tz 'zero' is not a finite number"},
      {good + "0,-1,0,2,0,0,0,1,1,0,0,100,100,1,1\n", ":3: pose_src '-1' is not an integer >= 0"},
      {good + "0,1,0,2,0,0,0,0,1,0,0,100,100,1,1\n", ":3: the quaternion is zero"},
      {good + "0,1,0,2,0,0,0,1,1,0,0,0,100,1,1\n", ":3: kappa must be > 0"},
      {good + "0,1,0,2,0,0,0,1,1,0,0,100,100,2,1\n", ":3: is_known_inlier must be 0 or 1"},
      {good + "0,1,0,1,0,0,0,1,1,0,0,100,100,1,1\n", ":3: a measurement from a pose to itself"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const std::string path = dir + "/bad" + std::to_string(k++) + ".csv";
    write(path, kHeader + c.body);
    const std::string what = error_of(path);
    EXPECT_NE(what.find(path + c.expected), std::string::npos) << what;
  }
  const std::string no_header = dir + "/noheader.csv";
  write(no_header, good);
  EXPECT_NE(error_of(no_header).find(no_header + ":1: expected the header line"),
            std::string::npos);
}

TEST(DpgoCsvReader, KnownInlierFlagsAreNeverRejectedByARobustSolve) {
  const GeneratorResult g = two_robot_grid(0.2);
  ASSERT_FALSE(g.outliers.empty());
  const std::string path = test::temp_dir() + "/flagged.csv";
  std::string text = kHeader;
  const std::size_t flagged = g.outliers.front();
  for (std::size_t e = 0; e < g.graph.num_measurements(); ++e)
    text += row(g.graph.measurements[e], 32, e == flagged);
  write(path, text);
  const DpgoCsvGraph r = read_dpgo_csv(path);
  GncCentralizedOptions o;
  o.robust.kind = RobustKind::kGncTls;
  o.known_inlier_flags = r.known_inlier;
  const GncCentralizedResult robust = solve_gnc_centralized(r.graph, o);
  EXPECT_EQ(robust.weights[flagged], 1.0);
  for (std::size_t e : robust.rejected) EXPECT_NE(e, flagged);
}

}  // namespace
}  // namespace tessera
