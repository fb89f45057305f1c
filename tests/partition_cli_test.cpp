// `tessera partition`: g2o and METIS input, --out / --json files, and clear errors.

#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "test_support.hpp"

namespace {

using tessera::test::bin;
using tessera::test::read_text_file;
using tessera::test::run_command;
using tessera::test::write_file;

// A 2D g2o graph without VERTEX lines: a chain of n poses plus loop closures.
std::string chain_g2o(int n) {
  std::ostringstream s;
  for (int v = 0; v + 1 < n; ++v) s << "EDGE_SE2 " << v << " " << v + 1 << " 1 0 0.1 1 0 0 1 0 1\n";
  for (int v = 10; v < n; v += 10) s << "EDGE_SE2 " << v - 7 << " " << v << " 0 1 0 1 0 0 1 0 1\n";
  return s.str();
}

int partition(const std::string& args, std::string* out) {
  return run_command(bin("tessera") + " partition " + args, out);
}

TEST(PartitionCli, G2oInputWritesAssignmentAndJson) {
  const std::string dir = tessera::test::temp_dir();
  const std::string g = write_file(dir, "chain.g2o", chain_g2o(60));
  std::string out;
  ASSERT_EQ(partition(g + " --parts 4 --preset eco --seed 3 --out " + dir + "/p.txt --json " + dir +
                          "/p.json",
                      &out),
            0)
      << out;
  EXPECT_NE(out.find("cut edges:"), std::string::npos) << out;
  std::istringstream lines(read_text_file(dir + "/p.txt"));
  int count = 0, block;
  while (lines >> block) {
    EXPECT_GE(block, 0);
    EXPECT_LT(block, 4);
    ++count;
  }
  EXPECT_EQ(count, 60);
  const std::string json = read_text_file(dir + "/p.json");
  for (const char* key : {"\"parts\": 4", "\"preset\": \"eco\"", "\"cut_edges\":", "\"cut_pairs\":",
                          "\"max_block_ratio\":", "\"cvolume\":", "\"time_ms\":",
                          "\"block_sizes\":", "\"imbalance\":", "\"n\": 60", "\"trace\":"})
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
}

// --objective rounds runs the colour pass (a "colours" phase in the trace) and the JSON reports
// the objective and the block adjacency graph.
TEST(PartitionCli, ObjectiveRoundsReportsTheBlockAdjacencyGraph) {
  const std::string dir = tessera::test::temp_dir();
  const std::string g = write_file(dir, "chain.g2o", chain_g2o(60));
  std::string out;
  ASSERT_EQ(
      partition(g + " --parts 4 --preset eco --objective rounds --json " + dir + "/p.json", &out),
      0)
      << out;
  EXPECT_NE(out.find("colours (objective rounds)"), std::string::npos) << out;
  const std::string json = read_text_file(dir + "/p.json");
  for (const char* key : {"\"objective\": \"rounds\"",
                          "\"colours\":", "\"adjacent_block_pairs\":", "\"phase\": \"colours\""})
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
}

// --islands reaches PartitionOptions::islands: highest with four islands traces island 3 and
// then its short island 4, and the JSON says how many were asked for.
TEST(PartitionCli, IslandsOptionSetsTheSearchCount) {
  const std::string dir = tessera::test::temp_dir();
  const std::string g = write_file(dir, "chain.g2o", chain_g2o(120));
  std::string out;
  ASSERT_EQ(
      partition(g + " --parts 3 --preset highest --islands 4 --json " + dir + "/p.json", &out), 0)
      << out;
  const std::string json = read_text_file(dir + "/p.json");
  EXPECT_NE(json.find("\"islands\": 4"), std::string::npos) << json;
  EXPECT_NE(json.find("island 3:"), std::string::npos) << json;
  EXPECT_NE(json.find("island 4: short"), std::string::npos) << json;  // the short island
  EXPECT_EQ(json.find("island 5:"), std::string::npos) << json;
}

TEST(PartitionCli, SequentialPresetIsContiguous) {
  const std::string dir = tessera::test::temp_dir();
  const std::string g = write_file(dir, "chain.g2o", chain_g2o(10));
  std::string out;
  ASSERT_EQ(partition(g + " --parts 3 --preset sequential --out -", &out), 0) << out;
  EXPECT_EQ(out.substr(0, 20), "0\n0\n0\n0\n1\n1\n1\n2\n2\n2\n") << out;
}

TEST(PartitionCli, MetisInputDetectedByContent) {
  const std::string dir = tessera::test::temp_dir();
  // Two triangles joined by the edge 3-4 (1-based ids), stored under a neutral name.
  const std::string g = write_file(dir, "two.txt", "6 7\n2 3\n1 3\n1 2 4\n3 5 6\n4 6\n4 5\n");
  std::string out;
  ASSERT_EQ(partition(g + " --parts 2 --eps 0 --json -", &out), 0) << out;
  EXPECT_NE(out.find("\"cut_edges\": 1,"), std::string::npos) << out;
  EXPECT_NE(out.find("\"block_sizes\": [3, 3]"), std::string::npos) << out;
}

TEST(PartitionCli, BadInputIsAClearError) {
  const std::string dir = tessera::test::temp_dir();
  const std::string g = write_file(dir, "chain.g2o", chain_g2o(20));
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {g + " --parts 21", "cannot split 20 vertices into 21"},
      {g + " --parts 0", "--parts: 0 is outside 1..64"},
      {g + " --parts 65", "--parts: 65 is outside 1..64"},
      {g + " --parts 2 --eps -0.5", "--eps: -0.5 is outside 0..1"},
      {g + " --parts 2 --islands 9", "--islands: 9 is outside 0..8"},
      {g + " --parts 2 --preset best", "unknown preset 'best'"},
      {g + " --parts 2 --objective speed", "unknown partition objective 'speed'"},
      {g + " --parts 2 --colour-slack 11", "--colour-slack: 11 is outside 0..10"},
      {g + " --parts 2 --time-limit -1", "--time-limit: must be >= 0"},
      {g + " --parts 2 --stall-steps -3", "--stall-steps: -3 is outside"},
      {g, "--parts N is required"},
      {g + " --parts 2 --colour red", "unknown option --colour"},
      {write_file(dir, "h.graph", "3 two\n2\n1 3\n2\n") + " --parts 2",
       "h.graph:1: bad METIS header"},
      {write_file(dir, "r.graph", "3 2\n2\n1 7\n2\n") + " --parts 2",
       "r.graph:3: vertex id 7 out of range 1..3"},
      {dir + "/missing.g2o --parts 2", "missing.g2o"},
  };
  for (const auto& c : cases) {
    std::string out;
    EXPECT_EQ(partition(c.args, &out), 2) << c.args << "\n" << out;
    EXPECT_NE(out.find(c.message), std::string::npos) << c.args << "\n" << out;
  }
}

TEST(PartitionCli, BenchmarkGraphIsBalanced) {
  TESSERA_REQUIRE_SHARED();
  std::string out;
  ASSERT_EQ(partition(tessera::test::shared_dir() +
                          "/datasets/CSAIL.g2o --parts 5 --preset fast --json -",
                      &out),
            0)
      << out;
  EXPECT_NE(out.find("\"n\": 1045"), std::string::npos) << out;
  EXPECT_NE(out.find("\"edges\": 1171"), std::string::npos) << out;
  const auto pos = out.find("\"max_block\": ");
  ASSERT_NE(pos, std::string::npos);
  EXPECT_LE(std::stoi(out.substr(pos + 13)), 215);  // floor(1.03 * 209)
}

}  // namespace
