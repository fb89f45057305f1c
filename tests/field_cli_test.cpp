// The field-data path through the command line: a generated multi-robot graph with GTSAM
// keys and stamps is read, described per robot, solved centralized and distributed (the
// sequential baseline = each robot its poses), written back per robot in TUM with the
// input's stamps, evaluated against the generator's ground truth and plotted.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tessera/graph/pose_keys.hpp>
#include <tessera/io/g2o_reader.hpp>

#include "test_support.hpp"

namespace {

using tessera::test::bin;
using tessera::test::contains;
using tessera::test::read_text_file;
using tessera::test::run_command;
using tessera::test::temp_dir;

struct Generated {
  std::string dir, graph, truth, stamps;
};

// 3 robots x 40 poses of the 2D city, GTSAM keys, stamps, ground truth as g2o.
Generated generate(const std::string& kind = "city", int poses = 120) {
  Generated g;
  g.dir = temp_dir();
  g.graph = g.dir + "/g.g2o";
  g.truth = g.dir + "/truth.g2o";
  g.stamps = g.dir + "/stamps.txt";
  std::string out;
  const int rc = run_command(bin("tessera") + " generate --kind " + kind + " --poses " +
                                 std::to_string(poses) + " --robots 3 --keys gtsam --out " +
                                 g.graph + " --truth " + g.truth + " --stamps " + g.stamps,
                             &out);
  EXPECT_EQ(rc, 0) << out;
  return g;
}

TEST(FieldCli, GeneratedGtsamFileIsReadWithItsRobots) {
  const Generated g = generate();
  const tessera::PoseKeys keys = tessera::read_g2o_file(g.graph).keys;
  EXPECT_EQ(keys.scheme, tessera::KeyScheme::kGtsam);
  EXPECT_EQ(keys.robot_names, (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(keys.id(0), tessera::gtsam_key('a', 0));
  EXPECT_EQ(keys.id(40), tessera::gtsam_key('b', 0));
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " info " + g.graph + " --json " + g.dir + "/i.json", &out),
            0)
      << out;
  EXPECT_TRUE(contains(out, "gtsam keys (robot = character in bits 56-63")) << out;
  EXPECT_TRUE(contains(out, "robots:                     3")) << out;
  EXPECT_TRUE(contains(out, "robot a           40 poses, 39 odometry")) << out;
  const std::string json = read_text_file(g.dir + "/i.json");
  EXPECT_TRUE(contains(json, "\"keys\": \"gtsam\"")) << json;
  EXPECT_TRUE(contains(json, "\"inter_robot_closures\"")) << json;
}

TEST(FieldCli, SolveWritesPerRobotTumWithTheInputStampsAndFrame) {
  const Generated g = generate();
  const std::string sol = g.dir + "/sol.g2o", tum = g.dir + "/tum";
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " solve " + g.graph + " --stamps " + g.stamps + " --out " +
                            sol + " --tum-dir " + tum,
                        &out),
            0)
      << out;
  EXPECT_TRUE(contains(out, "certified optimal")) << out;
  for (const char* r : {"a", "b", "c"}) {
    const std::string text = read_text_file(tum + "/robot_" + r + ".tum");
    EXPECT_TRUE(contains(text, "# robot " + std::string(r) + ": 40 poses")) << text;
    // Stamps are 1000 + 0.1 k: pose 39 of every robot at 1003.9.
    EXPECT_TRUE(contains(text, "\n1003.9 ")) << text;
  }
  // The solution keeps the input's ids and frame: pose a0 stays at its VERTEX value.
  const auto in = tessera::read_g2o_file(g.graph), res = tessera::read_g2o_file(sol);
  EXPECT_EQ(res.keys.ids, in.keys.ids);
  EXPECT_NEAR((res.graph.initial[0].t - in.graph.initial[0].t).norm(), 0, 1e-9);
  EXPECT_NEAR((res.graph.initial[0].R - in.graph.initial[0].R).norm(), 0, 1e-9);

  // eval against the ground truth: graph vs graph by id, folder vs graph by stamp.
  ASSERT_EQ(
      run_command(bin("tessera") + " eval " + sol + " " + g.truth + " --json " + g.dir + "/e.json",
                  &out),
      0)
      << out;
  EXPECT_TRUE(contains(out, "120 poses matched by index")) << out;
  const std::string json = read_text_file(g.dir + "/e.json");
  for (const char* field : {"\"ate\"", "\"rpe\"", "\"rmse\"", "\"median\"", "\"robots\""})
    EXPECT_TRUE(contains(json, field)) << json;
  ASSERT_EQ(
      run_command(bin("tessera") + " eval " + tum + " " + g.truth + " --stamps " + g.stamps, &out),
      0)
      << out;
  EXPECT_TRUE(contains(out, "120 poses matched by stamp")) << out;
  EXPECT_TRUE(contains(out, "team")) << out;
}

TEST(FieldCli, SequentialBaselineOfAGtsamFileIsOneBlockPerRobot) {
  const Generated g = generate("grid3d", 90);
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " solve " + g.graph +
                            " --algorithm rbcd --agents 3 --partition sequential --max-rounds 5",
                        &out),
            0)
      << out;
  // Robot ranges: a cut only by the rendezvous and inter-robot closures, which the info
  // command counts as inter-robot closures.
  std::string info;
  ASSERT_EQ(run_command(bin("tessera") + " info " + g.graph + " --json -", &info), 0) << info;
  const auto at = info.rfind("\"inter_robot_closures\": ");  // the team's, after "robots"
  ASSERT_NE(at, std::string::npos) << info;
  const std::string inter = info.substr(at + 24, info.find_first_of(",\n", at + 24) - at - 24);
  // ("(cut N)" or "(cut N, K colours)")
  EXPECT_TRUE(contains(out, "sequential partition (cut " + inter + ")") ||
              contains(out, "sequential partition (cut " + inter + ","))
      << out << info;
  ASSERT_EQ(run_command(bin("tessera") + " partition " + g.graph +
                            " --parts 3 --preset sequential --json -",
                        &out),
            0)
      << out;
  EXPECT_TRUE(contains(out, "\"cut_edges\": " + inter + ",")) << out;
}

TEST(FieldCli, PlotWritesAPng) {
  const Generated g = generate("grid3d", 90);
  const std::string png = g.dir + "/fig.png";
  std::string out;
  ASSERT_EQ(
      run_command(bin("tessera") + " plot " + g.graph + " --truth " + g.truth + " --out " + png,
                  &out),
      0)
      << out;
  std::ifstream in(png, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_GT(std::filesystem::file_size(png), 10000u);
  // Coloured by block, with cut and rejected measurements; a partition of the wrong size is
  // refused naming the file.
  ASSERT_EQ(run_command(bin("tessera") + " partition " + g.graph + " --parts 3 --out " + g.dir +
                            "/part.txt",
                        &out),
            0)
      << out;
  std::ofstream(g.dir + "/rej.txt")
      << tessera::gtsam_key('a', 0) << " " << tessera::gtsam_key('a', 1) << "\n5\n";
  ASSERT_EQ(run_command(bin("tessera") + " plot " + g.graph + " --partition " + g.dir +
                            "/part.txt --rejected " + g.dir + "/rej.txt --out " + png,
                        &out),
            0)
      << out;
  std::ofstream(g.dir + "/short.txt") << "0\n1\n";
  EXPECT_EQ(run_command(bin("tessera") + " plot " + g.graph + " --partition " + g.dir +
                            "/short.txt --out " + png,
                        &out),
            2)
      << out;
  EXPECT_TRUE(contains(out, g.dir + "/short.txt: 2 blocks for a graph of 90 poses")) << out;
  std::ofstream(g.dir + "/rej2.txt") << "3\n99999\n";
  EXPECT_EQ(run_command(bin("tessera") + " plot " + g.graph + " --rejected " + g.dir +
                            "/rej2.txt --out " + png,
                        &out),
            2)
      << out;
  EXPECT_TRUE(contains(out, g.dir + "/rej2.txt:2: measurement 99999 does not exist")) << out;
}

TEST(FieldCli, PlotReadsTheStampsFileItIsGiven) {
  const Generated g = generate("grid3d", 90);
  const std::string png = g.dir + "/fig.png";
  std::string out;
  // Accepted and used (as tessera eval uses it), not parsed and ignored: a missing file is named.
  EXPECT_EQ(run_command(bin("tessera") + " plot " + g.graph + " --truth " + g.truth + " --stamps " +
                            g.dir + "/missing.txt --out " + png,
                        &out),
            2)
      << out;
  EXPECT_TRUE(contains(out, g.dir + "/missing.txt")) << out;
  ASSERT_EQ(run_command(bin("tessera") + " plot " + g.graph + " --truth " + g.truth + " --stamps " +
                            g.stamps + " --out " + png,
                        &out),
            0)
      << out;
  EXPECT_FALSE(contains(out, "drawn unaligned")) << out;
  EXPECT_TRUE(std::filesystem::exists(png));
}

TEST(FieldCli, LaunchTakesItsOutputOptionsAlsoAsNameEqualsValue) {
  // A missing graph ends launch before any process starts, after its options are parsed.
  const std::string dir = tessera::test::temp_dir();
  for (const std::string flag : {"--out", "--tum", "--tum-dir", "--plot", "--keys", "--stamps"}) {
    std::string out;
    EXPECT_EQ(run_command(bin("tessera") + " launch " + dir + "/missing.g2o " + flag + "=x", &out),
              2)
        << flag << ": " << out;
    EXPECT_FALSE(contains(out, "unknown option")) << flag << ": " << out;
    EXPECT_TRUE(contains(out, dir + "/missing.g2o")) << flag << ": " << out;
  }
}

TEST(FieldCli, BadInputsExitTwoNamingFileAndLine) {
  const Generated g = generate();
  std::string out;
  const std::string bad = g.dir + "/bad.g2o";
  std::ofstream(bad) << read_text_file(g.graph) << "EDGE_SE2 3 4 1 0 0 1 0 0 1 0 1\n";
  EXPECT_EQ(run_command(bin("tessera") + " info " + bad + " --keys gtsam", &out), 2) << out;
  EXPECT_TRUE(contains(out, "is not a GTSAM key")) << out;
  EXPECT_TRUE(contains(out, bad + ":")) << out;
  std::ofstream(g.dir + "/s.txt") << "1 2\n";
  EXPECT_EQ(
      run_command(bin("tessera") + " solve " + g.graph + " --stamps " + g.dir + "/s.txt", &out), 2)
      << out;
  EXPECT_TRUE(contains(out, g.dir + "/s.txt:1: pose id 1 is not a pose of")) << out;
}

}  // namespace
