// The g2o reader: accepted quirks, every kind of bad input (message names file, line and
// problem), weights from information matrices, and the shared benchmark datasets.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/information_weights.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "g2o_text.hpp"
#include "test_support.hpp"

namespace {

using tessera::G2oReadOptions;
using tessera::G2oReadResult;
using tessera::InputError;
using tessera::test::expect_g2o_error;
using tessera::test::read_test_g2o;

const char* const kInfo2 = " 10 0 0 10 0 5";  // I11 I12 I13 I22 I23 I33
const std::string kInfo3 = " 4 0 0 0 0 0 4 0 0 0 0 4 0 0 0 6 0 0 6 0 6";

std::string edge2(int i, int j) {
  return "EDGE_SE2 " + std::to_string(i) + " " + std::to_string(j) + " 1 0 0" + kInfo2 + "\n";
}
std::string edge3(int i, int j, const std::string& q = "0 0 0 1") {
  return "EDGE_SE3:QUAT " + std::to_string(i) + " " + std::to_string(j) + " 1 0 0 " + q + kInfo3 +
         "\n";
}

// ---------------------------------------------------------------- accepted input

TEST(G2oReader, Reads2dVerticesAndEdges) {
  const auto r =
      read_test_g2o("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 2 1.5707963267948966\n" + edge2(0, 1));
  const auto& g = r.graph;
  EXPECT_EQ(g.d, 2);
  EXPECT_EQ(g.num_poses, 2u);
  ASSERT_EQ(g.num_measurements(), 1u);
  ASSERT_TRUE(g.has_initial());
  EXPECT_NEAR(g.initial[1].t(0), 1.0, 1e-15);
  EXPECT_NEAR(g.initial[1].t(1), 2.0, 1e-15);
  EXPECT_NEAR(g.initial[1].R(1, 0), 1.0, 1e-15);  // rotation by +90 degrees
  EXPECT_NEAR(g.initial[1].R(0, 1), -1.0, 1e-15);
  const auto& m = g.measurements[0];
  EXPECT_EQ(m.i, 0u);
  EXPECT_EQ(m.j, 1u);
  EXPECT_DOUBLE_EQ(m.t(0), 1.0);
  EXPECT_TRUE(m.R.isApprox(Eigen::Matrix2d::Identity()));
  EXPECT_DOUBLE_EQ(m.tau, 10.0);  // 2 / trace(inv(10 I2))
  EXPECT_DOUBLE_EQ(m.kappa, 5.0);
  EXPECT_EQ(g.source, "t.g2o");
  EXPECT_EQ(r.stats.vertex_lines, 2u);
  EXPECT_EQ(r.stats.components, 1u);
}

TEST(G2oReader, Reads3dVerticesAndEdges) {
  // Vertex 1 rotated by 90 degrees about z: q = (0, 0, sin 45, cos 45).
  const auto r = read_test_g2o(
      "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n"
      "VERTEX_SE3:QUAT 1 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n" +
      edge3(0, 1, "0 0 0.7071067811865476 0.7071067811865476"));
  const auto& g = r.graph;
  EXPECT_EQ(g.d, 3);
  EXPECT_EQ(g.num_poses, 2u);
  ASSERT_TRUE(g.has_initial());
  Eigen::Matrix3d rz;
  rz << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_TRUE(g.initial[1].R.isApprox(rz, 1e-12));
  EXPECT_DOUBLE_EQ(g.initial[1].t(2), 3.0);
  ASSERT_EQ(g.num_measurements(), 1u);
  EXPECT_TRUE(g.measurements[0].R.isApprox(rz, 1e-12));
  EXPECT_DOUBLE_EQ(g.measurements[0].tau, 4.0);    // 3 / trace(inv(4 I3))
  EXPECT_DOUBLE_EQ(g.measurements[0].kappa, 3.0);  // 3 / (2 trace(inv(6 I3)))
}

TEST(G2oReader, VerticesInAnyOrder) {
  for (const std::string order : {"0123", "3210", "0132", "2031"}) {
    std::string text = edge2(0, 1) + edge2(1, 2) + edge2(2, 3);
    for (char c : order) text += std::string("VERTEX_SE2 ") + c + " " + c + ".5 0 0\n";
    const auto r = read_test_g2o(text);
    ASSERT_EQ(r.graph.initial.size(), 4u) << order;
    for (int k = 0; k < 4; ++k) EXPECT_DOUBLE_EQ(r.graph.initial[k].t(0), k + 0.5) << order;
  }
}

TEST(G2oReader, SkipsBlankWhitespaceCommentAndFixLines) {
  const std::string text =
      "\n   \n\t\r\nVERTEX_SE2 0 0 0 0\r\n# a comment\nFIX 0\n  VERTEX_SE2\t1 0 0 0 \n\n" +
      edge2(0, 1) + "   ";  // the last line has no newline
  const auto r = read_test_g2o(text);
  EXPECT_EQ(r.graph.num_poses, 2u);
  EXPECT_EQ(r.graph.num_measurements(), 1u);
  EXPECT_EQ(r.stats.blank_lines, 5u);
  EXPECT_EQ(r.stats.comment_lines, 1u);
  EXPECT_EQ(r.stats.fix_lines, 1u);
  EXPECT_EQ(r.stats.lines, 10u);
}

TEST(G2oReader, NoVertexLinesGivesPosesFromEdgeIds) {
  const auto r = read_test_g2o(edge2(0, 1) + edge2(1, 2) + edge2(2, 3));
  EXPECT_EQ(r.graph.num_poses, 4u);
  EXPECT_TRUE(r.graph.initial.empty());
  EXPECT_FALSE(r.graph.has_initial());
  EXPECT_EQ(r.stats.vertex_lines, 0u);
}

TEST(G2oReader, BackwardEdgeKeptAsWritten) {
  const auto r = read_test_g2o(edge2(0, 1) + "EDGE_SE2 2 1 0.5 -0.25 0.3" + kInfo2 + "\n");
  ASSERT_EQ(r.graph.num_measurements(), 2u);
  const auto& m = r.graph.measurements[1];
  EXPECT_EQ(m.i, 2u);
  EXPECT_EQ(m.j, 1u);
  EXPECT_DOUBLE_EQ(m.t(0), 0.5);
  EXPECT_DOUBLE_EQ(m.t(1), -0.25);
  EXPECT_NEAR(m.R(1, 0), std::sin(0.3), 1e-15);
  EXPECT_EQ(r.stats.backward_edges, 1u);
}

TEST(G2oReader, ParallelEdgesAllKept) {
  const auto r = read_test_g2o(edge2(0, 1) + edge2(0, 1) + edge2(1, 0) + edge2(1, 2));
  EXPECT_EQ(r.graph.num_measurements(), 4u);
  EXPECT_EQ(r.stats.parallel_edges, 2u);
  EXPECT_EQ(r.stats.distinct_pairs, 2u);
  EXPECT_EQ(r.stats.backward_edges, 1u);
}

TEST(G2oReader, NonUnitQuaternionNormalisedByDefault) {
  // Twice a 90-degree rotation about x.
  const std::string text = edge3(0, 1, "1.4142135623730951 0 0 1.4142135623730951");
  const auto r = read_test_g2o(text);
  const Eigen::MatrixXd& R = r.graph.measurements[0].R;
  EXPECT_TRUE((R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-14));
  EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
  EXPECT_NEAR(R(2, 1), 1.0, 1e-14);
  EXPECT_NEAR(r.stats.max_quaternion_norm_error, 1.0, 1e-14);

  // Off: the unit-quaternion formula applied to the raw quaternion (not a rotation).
  G2oReadOptions raw;
  raw.normalize_quaternions = false;
  const Eigen::MatrixXd Rraw = read_test_g2o(text, raw).graph.measurements[0].R;
  EXPECT_NEAR(Rraw(0, 0), 1.0, 1e-14);
  EXPECT_NEAR(Rraw(1, 1), 1.0 - 4.0, 1e-14);
  EXPECT_NEAR(Rraw(2, 1), 4.0, 1e-14);
}

TEST(G2oReader, SlightlyNonUnitQuaternionLikeRealFiles) {
  const auto r = read_test_g2o(edge3(0, 1, "0 0 0.0001 1.0000001"));
  const Eigen::MatrixXd& R = r.graph.measurements[0].R;
  EXPECT_TRUE((R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-15));
}

TEST(G2oReader, NumbersParsedExactlyLikeStrtod) {
  // The reader has a fast path for plain decimals; it must round exactly like strtod.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mag(-30, 30);
  const char* const formats[] = {"%.6f", "%.7g", "%.17g", "%.3e", "%.15e", "%.0f", "%.20f"};
  std::vector<std::string> tokens = {"0",
                                     "-0",
                                     "1.",
                                     ".5",
                                     "-.25",
                                     "1e5",
                                     "1E-5",
                                     "+3.5",
                                     "9007199254740993",
                                     "0.1",
                                     "123456789012345678",
                                     "1.2345678901234567890123",
                                     "4.9e-324",
                                     "1e22",
                                     "1e23",
                                     "8.98846567431158e307",
                                     "0.000000",
                                     "100.000000"};
  char buf[64];
  for (int k = 0; k < 3000; ++k) {
    const double x = (rng() % 2 ? 1 : -1) * std::pow(10.0, mag(rng)) * (1 + (rng() % 1000) / 7.0);
    std::snprintf(buf, sizeof buf, formats[k % 7], x);
    tokens.push_back(buf);
  }
  std::string text;
  for (std::size_t k = 0; k < tokens.size(); ++k)
    text += "EDGE_SE2 " + std::to_string(k) + " " + std::to_string(k + 1) + " " + tokens[k] +
            " 0 0" + kInfo2 + "\n";
  const auto r = read_test_g2o(text);
  ASSERT_EQ(r.graph.num_measurements(), tokens.size());
  for (std::size_t k = 0; k < tokens.size(); ++k) {
    const double expected = std::strtod(tokens[k].c_str(), nullptr);
    const double got = r.graph.measurements[k].t(0);
    ASSERT_EQ(std::memcmp(&expected, &got, sizeof got), 0)
        << tokens[k] << ": " << got << " vs strtod " << expected;
  }
}

TEST(G2oReader, WeightsOfAKnownMatrix2d) {
  // T = [[4, 1], [1, 3]]: inv trace = (4 + 3) / (12 - 1) = 7/11, so tau = 22/7.
  const double upper[6] = {4, 1, 0.5, 3, -0.2, 7.5};
  const auto w = tessera::isotropic_weights_2d(upper);
  EXPECT_DOUBLE_EQ(w.tau, 22.0 / 7.0);
  EXPECT_DOUBLE_EQ(w.kappa, 7.5);
  const auto r = read_test_g2o("EDGE_SE2 0 1 0 0 0 4 1 0.5 3 -0.2 7.5\n");
  EXPECT_DOUBLE_EQ(r.graph.measurements[0].tau, 22.0 / 7.0);
  EXPECT_DOUBLE_EQ(r.graph.measurements[0].kappa, 7.5);
}

TEST(G2oReader, WeightsOfAKnownMatrix3d) {
  // A dense symmetric positive definite 6x6 matrix; compare with explicit inverses.
  Eigen::Matrix<double, 6, 6> A;
  A << 9, 1, 2, 0.5, 0.1, 0.3,   //
      1, 8, 1, 0.2, 0.4, 0.1,    //
      2, 1, 7, 0.3, 0.2, 0.6,    //
      0.5, 0.2, 0.3, 6, 1, 0.5,  //
      0.1, 0.4, 0.2, 1, 5, 0.7,  //
      0.3, 0.1, 0.6, 0.5, 0.7, 4;
  double upper[21];
  std::string values;
  int k = 0;
  for (int r = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c) {
      upper[k++] = A(r, c);
      values += " " + std::to_string(A(r, c));
    }
  const double tau = 3.0 / A.topLeftCorner<3, 3>().inverse().trace();
  const double kappa = 3.0 / (2.0 * A.bottomRightCorner<3, 3>().inverse().trace());
  const auto w = tessera::isotropic_weights_3d(upper);
  EXPECT_NEAR(w.tau, tau, 1e-13 * tau);
  EXPECT_NEAR(w.kappa, kappa, 1e-13 * kappa);
  EXPECT_TRUE(tessera::upper_triangle_is_positive_definite(upper, 6));

  const auto r = read_test_g2o("EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1" + values + "\n");
  EXPECT_NEAR(r.graph.measurements[0].tau, tau, 1e-13 * tau);
  EXPECT_NEAR(r.graph.measurements[0].kappa, kappa, 1e-13 * kappa);
  EXPECT_EQ(r.stats.non_pd_information, 0u);
}

TEST(G2oReader, WeightsRoundTripThroughInformationFromWeights) {
  for (int d : {2, 3}) {
    const auto upper = tessera::information_from_weights(d, 2.5, 40.0);
    const auto w = d == 2 ? tessera::isotropic_weights_2d(upper.data())
                          : tessera::isotropic_weights_3d(upper.data());
    EXPECT_DOUBLE_EQ(w.kappa, 2.5) << d;
    EXPECT_DOUBLE_EQ(w.tau, 40.0) << d;
  }
}

TEST(G2oReader, NonPositiveDefiniteInformationCountedAndWeightsKept) {
  // Like cubicle.g2o line 5753: a large translation-rotation cross term breaks definiteness,
  // but the blocks the weights use are fine.
  const std::string info = " 100 0 0 0 0 0 100 0 0 0 0 10 500 0 0 10 0 0 10 0 10";
  const auto r =
      read_test_g2o(edge3(0, 1) + "EDGE_SE3:QUAT 1 2 0 0 0 0 0 0 1" + info + "\n" + edge3(1, 2));
  EXPECT_EQ(r.stats.non_pd_information, 1u);
  EXPECT_EQ(r.stats.first_non_pd_line, 2u);
  const auto& m = r.graph.measurements[1];
  EXPECT_NEAR(m.tau, 3.0 / (1.0 / 100 + 1.0 / 100 + 1.0 / 10), 1e-12);
  EXPECT_NEAR(m.kappa, 10.0 / 2.0, 1e-12);
}

TEST(G2oReader, StreamAndFileVariants) {
  const std::string text = edge2(0, 1) + edge2(1, 2);
  std::istringstream in(text);
  const auto g = tessera::read_g2o(in, "stream.g2o");
  EXPECT_EQ(g.num_poses, 3u);
  EXPECT_EQ(g.source, "stream.g2o");
  const std::string path = tessera::test::write_file(tessera::test::temp_dir(), "f.g2o", text);
  const auto h = tessera::read_g2o(path);
  EXPECT_EQ(h.num_measurements(), 2u);
  EXPECT_EQ(h.source, path);
}

TEST(G2oReader, StreamThroughSmallBuffersEqualsInMemory) {
  // Lines straddle the read buffer's end, and one line is longer than the whole buffer.
  std::string text = "\xEF\xBB\xBFVERTEX_SE2 0 0 0 0\n\n";
  for (int k = 1; k < 60; ++k)
    text += "VERTEX_SE2 " + std::to_string(k) + " " + std::to_string(k * 0.37) + " 0 0.1\n";
  for (int k = 0; k + 1 < 60; ++k) text += edge2(k, k + 1) + "   \r\n";
  text += "EDGE_SE2 0 59 " + std::string(300, '0') + "1.5 0 0" + kInfo2;  // no final newline
  const auto expected = read_test_g2o(text);
  EXPECT_EQ(expected.graph.num_measurements(), 60u);
  EXPECT_DOUBLE_EQ(expected.graph.measurements.back().t(0), 1.5);
  for (std::size_t chunk : {1, 2, 7, 64, 100, 4096, 65536}) {
    G2oReadOptions options;
    options.read_chunk_bytes = chunk;
    std::istringstream in(text);
    const auto r = tessera::read_g2o_stream(in, "t.g2o", options);
    ASSERT_EQ(r.graph.num_measurements(), expected.graph.num_measurements()) << chunk;
    EXPECT_EQ(r.graph.num_poses, 60u);
    EXPECT_EQ(r.stats.lines, expected.stats.lines) << chunk;
    EXPECT_EQ(r.stats.blank_lines, 60u) << chunk;  // one empty, 59 whitespace-only
    for (std::size_t k = 0; k < r.graph.num_measurements(); ++k) {
      EXPECT_EQ(r.graph.measurements[k].t, expected.graph.measurements[k].t) << chunk;
      EXPECT_EQ(r.graph.measurements[k].i, expected.graph.measurements[k].i) << chunk;
    }
    for (std::size_t k = 0; k < 60; ++k)
      EXPECT_EQ(r.graph.initial[k].t, expected.graph.initial[k].t) << chunk;
  }
  // Errors name the same line whatever the buffer size.
  G2oReadOptions tiny;
  tiny.read_chunk_bytes = 3;
  std::istringstream bad(edge2(0, 1) + "\n" + edge2(1, 1));
  try {
    tessera::read_g2o_stream(bad, "t.g2o", tiny);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "t.g2o:3: self-loop: edge from pose 1 to itself");
  }
}

TEST(G2oReader, OptionsValidated) {
  G2oReadOptions options;
  options.read_chunk_bytes = 0;
  EXPECT_THROW(options.validate(), InputError);
  EXPECT_NE(tessera::test::input_error_of([&] {
              read_test_g2o(edge2(0, 1), options);
            }).find("read_chunk_bytes"),
            std::string::npos);
}

TEST(G2oReader, DisconnectedAllowedOnRequest) {
  G2oReadOptions options;
  options.allow_disconnected = true;
  const auto r = read_test_g2o(edge2(0, 1) + edge2(2, 3) + edge2(4, 5), options);
  EXPECT_EQ(r.stats.components, 3u);
  EXPECT_EQ(r.graph.num_poses, 6u);
}

// ---------------------------------------------------------------- bad input

TEST(G2oReaderErrors, UnknownTag) {
  expect_g2o_error(edge2(0, 1) + "EDGE_SE2_XY 0 1 2 3\n", "t.g2o:2: ", "unknown tag 'EDGE_SE2_XY'");
  expect_g2o_error("VERTEX_SE3:EULER 0 0 0 0 0 0 0\n", "t.g2o:1: ", "unknown tag");
}

TEST(G2oReaderErrors, WrongFieldCount) {
  expect_g2o_error(edge2(0, 1) + "EDGE_SE2 1 2 1 0 0 10 0 0 10 0\n",
                   "t.g2o:2: ", "EDGE_SE2 needs 11 values");
  expect_g2o_error(edge2(0, 1) + "EDGE_SE2 1 2 1 0 0 10 0 0 10 0 5 7\n", "t.g2o:2: ", "found 12");
  expect_g2o_error("VERTEX_SE2 0 0 0\n" + edge2(0, 1), "t.g2o:1: ", "VERTEX_SE2 needs 4 values");
  expect_g2o_error("VERTEX_SE3:QUAT 0 0 0 0 0 0 1\n",
                   "t.g2o:1: ", "VERTEX_SE3:QUAT needs 8 values");
  expect_g2o_error("EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1\n",
                   "t.g2o:1: ", "EDGE_SE3:QUAT needs 30 values");
  expect_g2o_error(edge2(0, 1) + "FIX\n", "t.g2o:2: ", "FIX needs at least one pose id");
}

TEST(G2oReaderErrors, NonNumericValue) {
  expect_g2o_error(edge2(0, 1) + "EDGE_SE2 1 2 1 abc 0" + kInfo2 + "\n",
                   "t.g2o:2: ", "EDGE_SE2 dy (column 5): 'abc' is not a number");
  expect_g2o_error("EDGE_SE2 0 1 1 0 0 10 0 0 10 0 5x\n", "t.g2o:1: ", "I33 (column 12): '5x'");
  expect_g2o_error("VERTEX_SE2 0 0 0 1..0\n", "t.g2o:1: ", "theta (column 5)");
  expect_g2o_error("EDGE_SE2 0 1 1 0 0 10 0 0 10 0 +-5\n", "t.g2o:1: ", "is not a number");
}

TEST(G2oReaderErrors, NonFiniteValue) {
  expect_g2o_error(edge2(0, 1) + "EDGE_SE2 1 2 nan 0 0" + kInfo2 + "\n",
                   "t.g2o:2: ", "dx (column 4): 'nan' is not finite");
  expect_g2o_error("EDGE_SE2 0 1 1 inf 0" + std::string(kInfo2) + "\n", "t.g2o:1: ", "not finite");
  expect_g2o_error("EDGE_SE2 0 1 1 0 0 10 0 0 1e999 0 5\n",
                   "t.g2o:1: ", "I22 (column 10): '1e999'");
  // Underflow is not an error: the value is just tiny.
  EXPECT_NO_THROW(read_test_g2o("EDGE_SE2 0 1 1e-400 0 0" + std::string(kInfo2) + "\n"));
}

TEST(G2oReaderErrors, ZeroQuaternion) {
  expect_g2o_error(edge3(0, 1) + edge3(1, 2, "0 0 0 0"), "t.g2o:2: ", "zero quaternion");
  expect_g2o_error(edge3(0, 1, "1e-9 0 0 1e-9"), "t.g2o:1: ", "zero quaternion");
  expect_g2o_error("VERTEX_SE3:QUAT 0 0 0 0 0 0 0 0\n", "t.g2o:1: ", "zero quaternion");
}

TEST(G2oReaderErrors, EdgeToMissingPose) {
  expect_g2o_error("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\n" + edge2(0, 1) + edge2(1, 5),
                   "t.g2o:4: ", "edge to missing pose 5");
  // The gap may also be inside the VERTEX ids.
  expect_g2o_error("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 2 0 0 0\n" + edge2(0, 1) + edge2(1, 2),
                   "t.g2o:3: ", "edge to missing pose 1");
}

TEST(G2oReaderIds, GapsInTheIdsAreNumberedInIdOrder) {
  // Ids need not be 0..n-1: the poses are numbered by increasing id and the ids kept.
  auto r = read_test_g2o(edge2(0, 1) + edge2(1, 3));
  EXPECT_EQ(r.graph.num_poses, 3u);
  EXPECT_EQ(r.keys.ids, (std::vector<std::uint64_t>{0, 1, 3}));
  EXPECT_EQ(r.graph.measurements[1].j, 2u);
  r = read_test_g2o("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 3 3 0 0\n" + edge2(0, 1) +
                    edge2(1, 3));
  ASSERT_EQ(r.graph.initial.size(), 3u);
  EXPECT_EQ(r.graph.initial[2].t(0), 3.0);
  // A huge id does not make the reader allocate for it.
  r = read_test_g2o(edge2(0, 1) + edge2(1, 2000000000));
  EXPECT_EQ(r.graph.num_poses, 3u);
  EXPECT_EQ(r.keys.id(2), 2000000000u);
}

TEST(G2oReaderErrors, SelfLoop) {
  expect_g2o_error(edge2(0, 1) + edge2(1, 1), "t.g2o:2: ", "self-loop: edge from pose 1 to itself");
}

TEST(G2oReaderErrors, Mixed2dAnd3d) {
  expect_g2o_error("VERTEX_SE2 0 0 0 0\n" + edge3(0, 1), "t.g2o:2: ",
                   "mixed 2D and 3D records: EDGE_SE3:QUAT here, but line 1 has VERTEX_SE2");
}

TEST(G2oReaderErrors, EmptyFile) {
  expect_g2o_error("", "t.g2o: ", "empty file");
  expect_g2o_error("\n  \n\n", "t.g2o: ", "no edges");
  expect_g2o_error("VERTEX_SE2 0 0 0 0\n", "t.g2o: ", "no edges");
}

TEST(G2oReaderErrors, Disconnected) {
  expect_g2o_error(edge2(0, 1) + edge2(2, 3) + edge2(4, 5),
                   "t.g2o: ", "disconnected: 3 connected components");
  // Isolated VERTEX poses are disconnected too.
  expect_g2o_error("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\nVERTEX_SE2 2 0 0 0\n" + edge2(0, 1),
                   "t.g2o: ", "no chain of edges links pose 2 to pose 0");
}

TEST(G2oReaderErrors, NegativeAndNonIntegerIds) {
  expect_g2o_error(edge2(0, 1) + "EDGE_SE2 -1 1 1 0 0" + kInfo2 + "\n",
                   "t.g2o:2: ", "pose id i '-1' is negative");
  expect_g2o_error("VERTEX_SE2 -3 0 0 0\n", "t.g2o:1: ", "pose id '-3' is negative");
  expect_g2o_error("EDGE_SE2 0 1.5 1 0 0" + std::string(kInfo2) + "\n",
                   "t.g2o:1: ", "pose id j '1.5' is not a non-negative integer");
  expect_g2o_error("EDGE_SE2 0 99999999999999999999999 1 0 0" + std::string(kInfo2) + "\n",
                   "t.g2o:1: ", "too large (at most 2^64 - 1)");
  expect_g2o_error(edge2(0, 1) + "FIX x\n", "t.g2o:2: ", "FIX pose id 'x'");
}

TEST(G2oReaderErrors, DuplicateVertexIds) {
  expect_g2o_error("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\nVERTEX_SE2 1 5 0 0\n" + edge2(0, 1),
                   "t.g2o:3: ", "duplicate VERTEX id 1 (first on line 2)");
}

TEST(G2oReaderErrors, UnusableWeights) {
  // Singular translation block: tau would be 0.
  expect_g2o_error("EDGE_SE2 0 1 1 0 0 1 1 0 1 0 5\n", "t.g2o:1: ", "translation weight tau");
  expect_g2o_error("EDGE_SE2 0 1 1 0 0 10 0 0 10 0 0\n", "t.g2o:1: ", "rotation weight kappa");
  expect_g2o_error("EDGE_SE2 0 1 1 0 0 -10 0 0 -10 0 5\n", "t.g2o:1: ", "translation weight tau");
  expect_g2o_error("EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1 4 0 0 0 0 0 4 0 0 0 0 4 0 0 0 0 0 0 0 0 0\n",
                   "t.g2o:1: ", "rotation weight kappa");
}

TEST(G2oReaderErrors, FileThatCannotBeOpened) {
  const std::string missing = tessera::test::temp_dir() + "/nope.g2o";
  try {
    tessera::read_g2o(missing);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(missing + ": cannot open the file", 0), 0u) << e.what();
  }
  const std::string dir = tessera::test::temp_dir();
  try {
    tessera::read_g2o(dir);
    ADD_FAILURE() << "no error for a directory";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), dir + ": cannot read the file: it is a directory");
  }
}

TEST(G2oReaderErrors, FileNameAndLineInMessageFromFile) {
  const std::string path = tessera::test::write_file(tessera::test::temp_dir(), "bad.g2o",
                                                     edge2(0, 1) + "\n" + edge2(1, 1));
  try {
    tessera::read_g2o(path);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":3: self-loop: edge from pose 1 to itself");
  }
}

TEST(G2oReaderErrors, LongLinesAndBinaryGarbage) {
  std::string long_line = "EDGE_SE2 0 1";
  for (int k = 0; k < 200000; ++k) long_line += " 1";
  expect_g2o_error(long_line + "\n", "t.g2o:1: ", "found 200002");
  std::string digits(1 << 20, '7');
  expect_g2o_error("EDGE_SE2 0 1 " + digits + " 0 0" + kInfo2 + "\n", "t.g2o:1: ", "not finite");
  std::string garbage;
  for (int k = 0; k < 5000; ++k) garbage += static_cast<char>((k * 7919) % 256);
  expect_g2o_error(garbage, "t.g2o:", "unknown tag");
  expect_g2o_error(std::string("EDGE_SE2\0 0 1", 13), "t.g2o:1: ", "unknown tag 'EDGE_SE2\\x00'");
}

// ---------------------------------------------------------------- shared datasets

struct ManifestRow {
  std::size_t poses = 0, edges = 0, vertex_lines = 0;
};

// Rows of MANIFEST.md's counts table: | file | paper | dim | VERTEX lines | poses n | EDGE lines |
std::map<std::string, ManifestRow> read_manifest(const std::string& path) {
  std::map<std::string, ManifestRow> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("| ", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line.substr(1));
    std::string cell;
    while (std::getline(ss, cell, '|')) {
      const auto b = cell.find_first_not_of(' '), e = cell.find_last_not_of(' ');
      cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
    }
    if (cells.size() < 6 || cells[0].size() < 5 ||
        cells[0].compare(cells[0].size() - 4, 4, ".g2o") != 0 ||
        cells[2].find('D') == std::string::npos)
      continue;
    rows[cells[0]] = {std::stoul(cells[4]), std::stoul(cells[5]), std::stoul(cells[3])};
  }
  return rows;
}

TEST(G2oReaderDatasets, EveryDatasetMatchesManifest) {
  TESSERA_REQUIRE_SHARED();
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(tessera::test::shared_dir()) / "datasets";
  const auto manifest = read_manifest((dir / "MANIFEST.md").string());
  ASSERT_GE(manifest.size(), 15u) << "could not parse the counts table of MANIFEST.md";
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".g2o") continue;
    const std::string name = entry.path().filename().string();
    SCOPED_TRACE(name);
    ++files;
    auto it = manifest.find(name);
    ASSERT_NE(it, manifest.end()) << "not listed in MANIFEST.md";
    const auto r = tessera::read_g2o_file(entry.path().string());
    EXPECT_EQ(r.graph.num_poses, it->second.poses);
    EXPECT_EQ(r.graph.num_measurements(), it->second.edges);
    EXPECT_EQ(r.stats.vertex_lines, it->second.vertex_lines);
    EXPECT_EQ(r.graph.has_initial(), it->second.vertex_lines > 0);
    EXPECT_EQ(r.stats.components, 1u);
    for (const auto& m : r.graph.measurements) {
      ASSERT_TRUE(m.kappa > 0 && m.tau > 0 && std::isfinite(m.kappa) && std::isfinite(m.tau));
      if (r.graph.d == 3) {
        ASSERT_LT((m.R.transpose() * m.R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
      }
    }
    // Quirk counts from MANIFEST.md's "Quirks a loader must handle".
    static const std::map<std::string, std::size_t> kBackward = {
        {"cubicle.g2o", 992}, {"kitti_00.g2o", 136},   {"kitti_02.g2o", 43}, {"kitti_05.g2o", 66},
        {"torus3D.g2o", 72},  {"smallGrid3D.g2o", 33}, {"MIT.g2o", 20},      {"tinyGrid3D.g2o", 1}};
    auto b = kBackward.find(name);
    EXPECT_EQ(r.stats.backward_edges, b == kBackward.end() ? 0u : b->second);
    EXPECT_EQ(r.stats.parallel_edges, name == "cubicle.g2o" ? 4383u : 0u);
    EXPECT_EQ(r.stats.non_pd_information, name == "cubicle.g2o" ? 5021u : 0u);
    if (name == "cubicle.g2o") {
      EXPECT_EQ(r.stats.first_non_pd_line, 5753u);
    }
    if (name.rfind("kitti_", 0) == 0) {
      EXPECT_EQ(r.stats.blank_lines, 1u);
    }
  }
  EXPECT_GE(files, 15u);
}

}  // namespace
