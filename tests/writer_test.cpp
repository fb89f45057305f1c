// g2o and TUM writers: exact round trips through the g2o reader, formats, errors.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/io/tum_writer.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "io/number_text.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

Eigen::MatrixXd random_rotation(int d, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  if (d == 2) return Eigen::Rotation2Dd(u(rng)).toRotationMatrix();
  Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
  return q.normalized().toRotationMatrix();
}

Pose random_pose(int d, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  Eigen::VectorXd t(d);
  for (int k = 0; k < d; ++k) t(k) = u(rng);
  return {random_rotation(d, rng), t};
}

// A connected graph (chain plus a few closures) with random measurements and weights.
PoseGraph random_graph(int d, std::size_t n, bool with_initial) {
  std::mt19937_64 rng(42 + d);
  std::uniform_real_distribution<double> w(0.01, 1e4);
  PoseGraph g;
  g.d = d;
  g.num_poses = n;
  auto add = [&](std::size_t i, std::size_t j) {
    Pose p = random_pose(d, rng);
    g.measurements.push_back({i, j, p.R, p.t, w(rng), w(rng)});
  };
  for (std::size_t k = 0; k + 1 < n; ++k) add(k, k + 1);
  add(n - 1, 0);  // backward edge: kept as written
  add(0, n / 2);
  add(0, n / 2);  // parallel edge
  if (with_initial)
    for (std::size_t k = 0; k < n; ++k) g.initial.push_back(random_pose(d, rng));
  return g;
}

void expect_same_graph(const PoseGraph& a, const PoseGraph& b) {
  ASSERT_EQ(a.d, b.d);
  ASSERT_EQ(a.num_poses, b.num_poses);
  ASSERT_EQ(a.num_measurements(), b.num_measurements());
  for (std::size_t e = 0; e < a.num_measurements(); ++e) {
    const Measurement &x = a.measurements[e], &y = b.measurements[e];
    EXPECT_EQ(x.i, y.i);
    EXPECT_EQ(x.j, y.j);
    EXPECT_EQ(x.t, y.t) << "translations are written in round-trip form: bit-exact";
    // Quaternion <-> matrix conversions cost a few ulps; nothing more.
    EXPECT_LE((x.R - y.R).cwiseAbs().maxCoeff(), 4e-15) << "edge " << e;
    EXPECT_NEAR(x.tau, y.tau, 1e-15 * x.tau);
    EXPECT_NEAR(x.kappa, y.kappa, 1e-15 * x.kappa);
  }
  ASSERT_EQ(a.initial.size(), b.initial.size());
  for (std::size_t k = 0; k < a.initial.size(); ++k) {
    EXPECT_EQ(a.initial[k].t, b.initial[k].t);
    EXPECT_LE((a.initial[k].R - b.initial[k].R).cwiseAbs().maxCoeff(), 4e-15);
  }
}

TEST(NumberText, ShortestRoundTripForm) {
  std::string s;
  append_number(s, 0.1);
  s += ' ';
  append_number(s, 10.0);
  s += ' ';
  append_number(s, -0.0);
  s += ' ';
  append_number(s, 1e-300);
  EXPECT_EQ(s, "0.1 10 0 1e-300");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1e6, 1e6);
  for (int k = 0; k < 10000; ++k) {
    const double x = u(rng) * std::pow(10.0, double(k % 40) - 20.0);
    std::string text;
    append_number(text, x);
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), x) << text;
  }
}

TEST(G2oWriter, RoundTrip2dThroughTheReader) {
  const std::string dir = test::temp_dir();
  const PoseGraph g = random_graph(2, 50, true);
  write_g2o(g, dir + "/g.g2o");
  expect_same_graph(g, read_g2o(dir + "/g.g2o"));
}

TEST(G2oWriter, RoundTrip3dThroughTheReader) {
  const std::string dir = test::temp_dir();
  const PoseGraph g = random_graph(3, 50, true);
  write_g2o(g, dir + "/g.g2o");
  expect_same_graph(g, read_g2o(dir + "/g.g2o"));
}

TEST(G2oWriter, WithoutVerticesWritesOnlyEdges) {
  const std::string dir = test::temp_dir();
  const PoseGraph g = random_graph(3, 10, false);
  write_g2o(g, dir + "/g.g2o");
  const std::string text = test::read_text_file(dir + "/g.g2o");
  EXPECT_EQ(text.find("VERTEX"), std::string::npos);
  EXPECT_EQ(text.rfind("EDGE_SE3:QUAT 0 1 ", 0), 0u) << text.substr(0, 80);
  expect_same_graph(g, read_g2o(dir + "/g.g2o"));
}

TEST(G2oWriter, ExplicitPosesBecomeVertices) {
  const std::string dir = test::temp_dir();
  PoseGraph g = random_graph(2, 10, false);
  const PoseGraph with = random_graph(2, 10, true);
  write_g2o(g, with.initial, dir + "/g.g2o");
  g.initial = with.initial;
  expect_same_graph(g, read_g2o(dir + "/g.g2o"));
}

TEST(G2oWriter, LineFormatAndInformationMatrix) {
  const std::string dir = test::temp_dir();
  PoseGraph g;
  g.d = 2;
  g.num_poses = 2;
  Eigen::VectorXd t(2);
  t << 1.5, -2;
  g.measurements.push_back({0, 1, Eigen::Rotation2Dd(0.25).toRotationMatrix(), t, 7.0, 3.0});
  g.initial = {Pose::identity(2), Pose::identity(2)};
  write_g2o(g, dir + "/g.g2o");
  EXPECT_EQ(test::read_text_file(dir + "/g.g2o"),
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\nEDGE_SE2 0 1 1.5 -2 0.25 3 0 0 3 0 7\n");

  g.d = 3;
  Eigen::VectorXd t3(3);
  t3 << 1, 2, 3;
  g.measurements = {{0, 1, Eigen::Matrix3d::Identity(), t3, 7.0, 3.0}};
  g.initial.clear();
  write_g2o(g, dir + "/g3.g2o");
  EXPECT_EQ(test::read_text_file(dir + "/g3.g2o"),
            "EDGE_SE3:QUAT 0 1 1 2 3 0 0 0 1 3 0 0 0 0 0 3 0 0 0 0 3 0 0 0 14 0 0 14 0 14\n");
}

TEST(G2oWriter, ErrorsNameThePath) {
  const PoseGraph g = random_graph(2, 5, true);
  try {
    write_g2o(g, "/nonexistent-dir/x.g2o");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.g2o"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
  const std::string dir = test::temp_dir();
  std::vector<Pose> too_few(3, Pose::identity(2));
  EXPECT_NE(test::input_error_of([&] {
              write_g2o(g, too_few, dir + "/y.g2o");
            }).find("3 vertex poses given for a graph of 5 poses"),
            std::string::npos);
}

std::vector<std::vector<double>> read_tum(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::vector<double> row;
    for (double x; fields >> x;) row.push_back(x);
    rows.push_back(row);
  }
  return rows;
}

TEST(TumWriter, OneLinePerPoseWithIndexTimestamps3d) {
  const std::string dir = test::temp_dir();
  std::mt19937_64 rng(3);
  std::vector<Pose> poses;
  for (int k = 0; k < 20; ++k) poses.push_back(random_pose(3, rng));
  write_tum(poses, dir + "/t.tum");
  const auto rows = read_tum(dir + "/t.tum");
  ASSERT_EQ(rows.size(), poses.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    ASSERT_EQ(rows[k].size(), 8u);
    EXPECT_EQ(rows[k][0], double(k));
    for (int c = 0; c < 3; ++c) EXPECT_EQ(rows[k][1 + c], poses[k].t(c));
    EXPECT_GE(rows[k][7], 0.0) << "qw >= 0";
    Eigen::Quaterniond q(rows[k][7], rows[k][4], rows[k][5], rows[k][6]);
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_LE((q.toRotationMatrix() - poses[k].R).cwiseAbs().maxCoeff(), 1e-14);
  }
}

TEST(TumWriter, PlanarPosesLieAtZEqualsZeroRotatingAboutZ) {
  const std::string dir = test::temp_dir();
  Eigen::VectorXd t(2);
  t << 1.25, -4;
  write_tum({{Eigen::Rotation2Dd(1.0).toRotationMatrix(), t}, Pose::identity(2)}, dir + "/t.tum");
  const auto rows = read_tum(dir + "/t.tum");
  ASSERT_EQ(rows.size(), 2u);
  const std::vector<double> expected = {0, 1.25, -4, 0, 0, 0, std::sin(0.5), std::cos(0.5)};
  ASSERT_EQ(rows[0].size(), 8u);
  for (int c = 0; c < 8; ++c) EXPECT_NEAR(rows[0][c], expected[c], 1e-15) << c;
  EXPECT_EQ(test::read_text_file(dir + "/t.tum")
                .substr(test::read_text_file(dir + "/t.tum").find('\n') + 1),
            "1 0 0 0 0 0 0 1\n");
}

TEST(TumWriter, CannotOpenNamesThePath) {
  try {
    write_tum({Pose::identity(3)}, "/nonexistent-dir/t.tum");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/t.tum"), std::string::npos);
  }
}

}  // namespace
}  // namespace tessera
