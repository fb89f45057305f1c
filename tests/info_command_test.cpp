// `tessera info`: figures printed and written as JSON, bad input exits 2 with file:line.

#include <gtest/gtest.h>

#include <string>

#include "test_support.hpp"

namespace {

using tessera::test::bin;
using tessera::test::contains;
using tessera::test::read_text_file;
using tessera::test::run_command;
using tessera::test::temp_dir;
using tessera::test::write_file;

const std::string kInfo2 = " 10 0 0 10 0 5";

std::string edge2(int i, int j) {
  return "EDGE_SE2 " + std::to_string(i) + " " + std::to_string(j) + " 1 0 0" + kInfo2 + "\n";
}

TEST(InfoCommand, PrintsFiguresAndJson) {
  const std::string dir = temp_dir();
  // Poses 0..3, a backward edge (2,1) and a parallel edge on {0,1}; no VERTEX lines.
  const std::string graph = write_file(
      dir, "g.g2o",
      edge2(0, 1) + "\n" + edge2(1, 0) + "EDGE_SE2 2 1 1 0 0" + kInfo2 + "\n" + edge2(2, 3));
  const std::string json = dir + "/info.json";
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " info " + graph + " --json " + json, &out), 0) << out;
  EXPECT_TRUE(contains(out, "poses:                      4")) << out;
  EXPECT_TRUE(contains(out, "edges:                      4")) << out;
  EXPECT_TRUE(contains(out, "dimension:                  2D")) << out;
  EXPECT_TRUE(contains(out, "parallel edges:             1")) << out;
  EXPECT_TRUE(contains(out, "backward edges (i > j):     2")) << out;
  EXPECT_TRUE(contains(out, "VERTEX lines:               none")) << out;

  const std::string j = read_text_file(json);
  EXPECT_TRUE(contains(j, "\"poses\": 4,")) << j;
  EXPECT_TRUE(contains(j, "\"edges\": 4,")) << j;
  EXPECT_TRUE(contains(j, "\"d\": 2,")) << j;
  EXPECT_TRUE(contains(j, "\"components\": 1,")) << j;
  EXPECT_TRUE(contains(j, "\"parallel_edges\": 1,")) << j;
  EXPECT_TRUE(contains(j, "\"backward_edges\": 2,")) << j;
  EXPECT_TRUE(contains(j, "\"non_pd_information\": 0,")) << j;
  EXPECT_TRUE(contains(j, "\"has_vertices\": false,")) << j;
  EXPECT_TRUE(contains(j, "\"blank_lines\": 1,")) << j;
  EXPECT_TRUE(contains(j, "\"graph\": \"" + graph + "\"")) << j;
  EXPECT_EQ(j.front(), '{');
  EXPECT_EQ(j.substr(j.size() - 2), "}\n");
  // Valid JSON as far as python can tell, when python is there.
  std::string py;
  if (run_command("command -v python3", &py) == 0) {
    EXPECT_EQ(run_command("python3 -m json.tool " + json + " > /dev/null", &py), 0) << py;
  }
}

TEST(InfoCommand, AcceptsDisconnectedGraph) {
  const std::string graph = write_file(temp_dir(), "d.g2o", edge2(0, 1) + edge2(2, 3));
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " info " + graph + " --json -", &out), 0) << out;
  EXPECT_TRUE(contains(out, "connected components:       2")) << out;
  EXPECT_TRUE(contains(out, "\"components\": 2,")) << out;
}

TEST(InfoCommand, ReportsNonPdInformationAnd3d) {
  const std::string nonpd = " 100 0 0 0 0 0 100 0 0 0 0 10 500 0 0 10 0 0 10 0 10";
  const std::string graph =
      write_file(temp_dir(), "c.g2o",
                 "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 0 0 0 0 0 0 1\n"
                 "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1" +
                     nonpd + "\n");
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " info " + graph + " --json -", &out), 0) << out;
  EXPECT_TRUE(contains(out, "dimension:                  3D")) << out;
  EXPECT_TRUE(contains(out, "non-PD information:         1  (first on line 3")) << out;
  EXPECT_TRUE(contains(out, "\"has_vertices\": true,")) << out;
  EXPECT_TRUE(contains(out, "\"first_non_pd_line\": 3,")) << out;
}

TEST(InfoCommand, BadInputExitsTwoWithFileAndLine) {
  const std::string graph = write_file(temp_dir(), "bad.g2o", edge2(0, 1) + "EDGE_SE2 1 2 x\n");
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " info " + graph, &out), 2);
  EXPECT_TRUE(contains(out, graph + ":2: EDGE_SE2 needs 11 values")) << out;

  EXPECT_EQ(run_command(bin("tessera") + " info " + temp_dir() + "/missing.g2o", &out), 2);
  EXPECT_TRUE(contains(out, "missing.g2o: cannot open the file")) << out;
}

TEST(InfoCommand, UsageErrorsAndHelp) {
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " info", &out), 2);
  EXPECT_TRUE(contains(out, "missing GRAPH")) << out;
  EXPECT_EQ(run_command(bin("tessera") + " info a.g2o b.g2o", &out), 2);
  EXPECT_TRUE(contains(out, "more than one GRAPH")) << out;
  EXPECT_EQ(run_command(bin("tessera") + " info x.g2o --frobnicate", &out), 2);
  EXPECT_TRUE(contains(out, "unknown option --frobnicate")) << out;
  EXPECT_EQ(run_command(bin("tessera") + " info --help", &out), 0);
  EXPECT_TRUE(contains(out, "usage: tessera info GRAPH")) << out;
}

TEST(InfoCommand, CubicleDataset) {
  TESSERA_REQUIRE_SHARED();
  const std::string graph = tessera::test::shared_dir() + "/datasets/cubicle.g2o";
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " info " + graph + " --json -", &out), 0) << out;
  EXPECT_TRUE(contains(out, "\"poses\": 5750,")) << out;
  EXPECT_TRUE(contains(out, "\"edges\": 16869,")) << out;
  EXPECT_TRUE(contains(out, "\"parallel_edges\": 4383,")) << out;
  EXPECT_TRUE(contains(out, "\"backward_edges\": 992,")) << out;
  EXPECT_TRUE(contains(out, "\"non_pd_information\": 5021,")) << out;
}

}  // namespace
