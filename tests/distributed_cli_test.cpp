// `tessera solve --algorithm rbcd|rbcd++|irbcd`: JSON fields, trace rows, errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>
#include <tessera/io/g2o_writer.hpp>

#include "random_graph.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::string graph_file(const std::string& dir) {
  test::RandomGraphSpec spec;
  spec.d = 2;
  spec.poses = 60;
  spec.loop_closures = 30;
  const PoseGraph g = test::random_pose_graph(spec);
  const std::string path = dir + "/g.g2o";
  write_g2o(g, path);
  return path;
}

TEST(DistributedCli, JsonAndTrace) {
  const std::string dir = test::temp_dir();
  const std::string g = graph_file(dir);
  for (const char* alg : {"rbcd", "rbcd++", "irbcd"}) {
    std::string out;
    const std::string cmd = test::bin("tessera") + " solve " + g + " --algorithm " + alg +
                            " --agents 3 --partition fast --reference --json " + dir +
                            "/r.json --trace " + dir + "/t.csv --out " + dir + "/o.g2o";
    ASSERT_EQ(test::run_command(cmd, &out), 0) << out;
    const std::string j = test::read_text_file(dir + "/r.json");
    for (const char* key :
         {"\"algorithm\"", "\"graph\"", "\"poses\"", "\"edges\"", "\"d\"", "\"rank\"",
          "\"iterations\"", "\"grad_norm\"", "\"cost\"", "\"certified\": null", "\"wall_s\"",
          "\"agents\": 3", "\"partition\": \"fast\"", "\"rounds\"", "\"restarts\"",
          "\"bytes_exchanged\"", "\"rel_gap\"", "\"stop_reason\": \"grad_norm\""})
      EXPECT_NE(j.find(key), std::string::npos) << key << " in\n" << j;
    EXPECT_EQ(j.find("\"rel_gap\": null"), std::string::npos);
    const std::string t = test::read_text_file(dir + "/t.csv");
    EXPECT_EQ(t.rfind("round,cost,grad_norm,selected,restart,bytes", 0), 0u);
    EXPECT_GT(std::count(t.begin(), t.end(), '\n'), 2);
    EXPECT_FALSE(test::read_text_file(dir + "/o.g2o").empty());
  }
}

// Every algorithm's summary starts with the same fields in the same order (cli/solve_output),
// and --out picks the format by the file name: TUM for ".tum", g2o otherwise.
TEST(DistributedCli, EveryAlgorithmSharesTheSummaryHeadAndThePoseFileFormats) {
  const std::string dir = test::temp_dir();
  const std::string g = graph_file(dir);
  for (const char* alg : {"centralized", "irbcd"}) {
    std::string out;
    const std::string cmd = test::bin("tessera") + " solve " + g + " --algorithm " + alg +
                            " --json " + dir + "/r.json --out " + dir + "/o.tum --tum " + dir +
                            "/t.tum";
    ASSERT_EQ(test::run_command(cmd, &out), 0) << out;
    const std::string j = test::read_text_file(dir + "/r.json");
    EXPECT_EQ(j.find(std::string("\"algorithm\": \"") + alg + "\""), 4u) << j;
    std::size_t at = 0;
    for (const char* key :
         {"\"algorithm\"", "\"graph\"", "\"poses\": 60", "\"edges\"", "\"d\": 2", "\"rank\"",
          "\"iterations\"", "\"grad_norm\"", "\"cost\"", "\"relaxation_cost\"", "\"certified\""}) {
      const std::size_t found = j.find(key);
      ASSERT_NE(found, std::string::npos) << key << " in\n" << j;
      EXPECT_GE(found, at) << key << " out of order in\n" << j;
      at = found;
    }
    // --out with ".tum" writes the same TUM text as --tum; a ".g2o" name writes vertices and
    // the graph's edges.
    EXPECT_EQ(test::read_text_file(dir + "/o.tum"), test::read_text_file(dir + "/t.tum")) << alg;
    EXPECT_EQ(test::read_text_file(dir + "/o.tum").find("VERTEX"), std::string::npos) << alg;
    ASSERT_EQ(test::run_command(test::bin("tessera") + " solve " + g + " --algorithm " + alg +
                                    " --out " + dir + "/o.g2o",
                                &out),
              0)
        << out;
    const std::string written = test::read_text_file(dir + "/o.g2o");
    EXPECT_EQ(written.rfind("VERTEX_SE2 0 ", 0), 0u) << alg;
    EXPECT_EQ(occurrences(written, "VERTEX_SE2 "), 60u) << alg;
    EXPECT_EQ(occurrences(written, "EDGE_SE2 "), occurrences(test::read_text_file(g), "EDGE_SE2 "))
        << alg;
  }
}

// Parallel rounds (a colour class per round) are the default; --sequential restores one block
// per round; the two switches exclude each other.
TEST(DistributedCli, ParallelByDefaultSequentialOnRequest) {
  const std::string dir = test::temp_dir();
  // A chain: 4 sequential blocks form a path 0-1-2-3. Started from the ground truth (the file's
  // poses), not the chordal solution, which is exact on a tree.
  test::RandomGraphSpec spec;
  spec.d = 2;
  spec.poses = 60;
  spec.loop_closures = 0;
  const std::string g = dir + "/chain.g2o";
  write_g2o(test::random_pose_graph(spec), g);
  auto run = [&](const std::string& flags, std::string* out) {
    return test::run_command(
        test::bin("tessera") + " solve " + g +
            " --algorithm irbcd --agents 4 --partition sequential --init file --json " + dir +
            "/p.json --trace " + dir + "/p.csv " + flags,
        out);
  };
  // Selected blocks per round, from the trace's `selected` column ("0;2" = two blocks).
  auto most_selected = [&] {
    std::istringstream t(test::read_text_file(dir + "/p.csv"));
    std::string line;
    std::getline(t, line);
    std::size_t most = 0;
    while (std::getline(t, line)) {
      std::vector<std::string> cols;
      std::stringstream ls(line);
      for (std::string c; std::getline(ls, c, ',');) cols.push_back(c);
      if (cols.size() < 4 || cols[3].empty()) continue;
      most = std::max<std::size_t>(
          most, 1 + static_cast<std::size_t>(std::count(cols[3].begin(), cols[3].end(), ';')));
    }
    return most;
  };
  std::string out;
  ASSERT_EQ(run("", &out), 0) << out;
  EXPECT_NE(test::read_text_file(dir + "/p.json").find("\"parallel\": true"), std::string::npos);
  EXPECT_EQ(most_selected(), 2u);  // a chain of 4 blocks: classes {0,2} and {1,3}
  ASSERT_EQ(run("--sequential", &out), 0) << out;
  EXPECT_NE(test::read_text_file(dir + "/p.json").find("\"parallel\": false"), std::string::npos);
  EXPECT_EQ(most_selected(), 1u);
  EXPECT_EQ(run("--parallel --sequential", &out), 2);
  EXPECT_NE(out.find("--sequential"), std::string::npos) << out;
}

// A partition written by `tessera partition --out` and given back with --partition-file solves
// exactly as the same search run inside `solve` (same blocks, same iterates); a file that does
// not fit the run is refused, naming the file.
TEST(DistributedCli, APartitionFileSolvesLikeTheSameSearchInsideSolve) {
  const std::string dir = test::temp_dir();
  const std::string g = graph_file(dir);
  const std::string tessera = test::bin("tessera");
  std::string out;
  ASSERT_EQ(test::run_command(tessera + " partition " + g +
                                  " --parts 3 --preset eco --objective rounds --seed 1 --out " +
                                  dir + "/p.txt",
                              &out),
            0)
      << out;
  const std::string solve = tessera + " solve " + g + " --algorithm irbcd --trace ";
  ASSERT_EQ(test::run_command(
                solve + dir + "/a.csv --agents 3 --partition eco --json " + dir + "/a.json", &out),
            0)
      << out;
  ASSERT_EQ(test::run_command(solve + dir + "/b.csv --agents 3 --partition-file " + dir +
                                  "/p.txt --json " + dir + "/b.json",
                              &out),
            0)
      << out;
  // The trace's last column is wall time: compare round, cost, gradient, selection, restart.
  auto without_times = [](const std::string& csv) {
    std::istringstream in(csv);
    std::string line, kept;
    while (std::getline(in, line)) kept += line.substr(0, line.rfind(',')) + "\n";
    return kept;
  };
  EXPECT_EQ(without_times(test::read_text_file(dir + "/a.csv")),
            without_times(test::read_text_file(dir + "/b.csv")));
  const std::string a = test::read_text_file(dir + "/a.json");
  const std::string b = test::read_text_file(dir + "/b.json");
  EXPECT_NE(b.find("\"partition\": \"file\""), std::string::npos) << b;
  for (const char* key : {"\"cut_edges\"", "\"colours\"", "\"adjacent_block_pairs\""}) {
    const std::size_t at = a.find(key), bt = b.find(key);
    ASSERT_NE(at, std::string::npos) << key;
    ASSERT_NE(bt, std::string::npos) << key;
    EXPECT_EQ(a.substr(at, a.find(',', at) - at), b.substr(bt, b.find(',', bt) - bt)) << key;
  }
  EXPECT_EQ(
      test::run_command(solve + dir + "/c.csv --agents 2 --partition-file " + dir + "/p.txt", &out),
      2);
  EXPECT_NE(out.find("p.txt"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(solve + dir + "/c.csv --agents 3 --partition eco --partition-file " +
                                  dir + "/p.txt",
                              &out),
            2);
  EXPECT_NE(out.find("exclude"), std::string::npos) << out;
}

TEST(DistributedCli, RejectsBadOptions) {
  const std::string dir = test::temp_dir();
  const std::string g = graph_file(dir);
  std::string out;
  EXPECT_EQ(test::run_command(
                test::bin("tessera") + " solve " + g + " --algorithm irbcd --agents 0", &out),
            2);
  EXPECT_NE(out.find("--agents"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(
                test::bin("tessera") + " solve " + g + " --algorithm irbcd --select best", &out),
            2);
  EXPECT_NE(out.find("uniform"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(
                test::bin("tessera") + " solve " + g + " --algorithm irbcd --grad-tol -1", &out),
            2);
  EXPECT_NE(out.find("grad_norm_tol"), std::string::npos) << out;
  EXPECT_EQ(
      test::run_command(
          test::bin("tessera") + " solve " + g + " --algorithm irbcd --tangent-radius 0", &out),
      2);
  EXPECT_NE(out.find("tangent_radius_scale"), std::string::npos) << out;
  EXPECT_EQ(
      test::run_command(
          test::bin("tessera") + " solve " + g + " --algorithm irbcd --tangent-dots fast", &out),
      2);
  EXPECT_NE(out.find("--tangent-dots"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + g +
                                  " --algorithm irbcd --irbcd-grad-reduction 1",
                              &out),
            2);
  EXPECT_NE(out.find("irbcd_grad_reduction"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(
                test::bin("tessera") + " solve " + g + " --algorithm rbcd++ --tr-grad-reduction -1",
                &out),
            2);
  EXPECT_NE(out.find("grad_reduction"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + g + " --algorithm sgd", &out), 2);
  EXPECT_NE(out.find("irbcd"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + g +
                                  " --algorithm irbcd --robust gnc-tls --gnc-mu-hold rises",
                              &out),
            2);
  EXPECT_NE(out.find("--gnc-mu-hold"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(test::bin("tessera") + " solve " + g +
                                  " --algorithm irbcd --robust gnc-tls --gnc-step-trust 2",
                              &out),
            2);
  EXPECT_NE(out.find("--gnc-step-trust"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera
