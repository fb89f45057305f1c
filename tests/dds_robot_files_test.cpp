// One file per robot (core/runtime/robot_file.hpp, `tessera generate --split`, `tessera launch
// DIR`): reading a robot's own file gives the same share as taking its part of the whole file, and
// a run from per-robot files gives the same result as from the single file.
// Domains used here: 203-204 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/partition/graph_structure.hpp>
#include <tessera/partition/partitioner.hpp>
#include <tessera/util/input_error.hpp>

#include "dds_process_support.hpp"
#include "runtime/local_share.hpp"
#include "runtime/preloaded_graph.hpp"
#include "runtime/robot_file.hpp"

namespace tessera::test::dds {
namespace {

// Generates a graph and its per-robot split; returns the whole file's path.
std::string generate_split(const std::string& dir, const std::string& kind, int poses, int robots,
                           bool strip_vertices = false) {
  const std::string whole = dir + "/whole.g2o";
  std::string out;
  EXPECT_EQ(run_command(bin("tessera") + " generate --kind " + kind + " --poses " +
                            std::to_string(poses) + " --robots " + std::to_string(robots) +
                            " --seed 4 --out " + whole + " --split " + dir + "/robots",
                        &out),
            0)
      << out;
  if (strip_vertices) {
    for (int r = 0; r < robots; ++r) {
      const std::string p = dir + "/robots/robot" + std::to_string(r) + ".g2o";
      std::istringstream in(slurp(p));
      std::ofstream o(p);
      for (std::string line; std::getline(in, line);)
        if (line.rfind("VERTEX", 0) != 0) o << line << "\n";
    }
  }
  return whole;
}

void expect_same_share(const agent::RobotShare& a, const agent::RobotShare& b) {
  EXPECT_EQ(a.begin, b.begin);
  EXPECT_EQ(a.end, b.end);
  EXPECT_EQ(a.d, b.d);
  ASSERT_EQ(a.measurements.size(), b.measurements.size());
  EXPECT_EQ(a.measurement_index, b.measurement_index);
  for (std::size_t k = 0; k < a.measurements.size(); ++k) {
    const Measurement &x = a.measurements[k], &y = b.measurements[k];
    ASSERT_EQ(x.i, y.i);
    ASSERT_EQ(x.j, y.j);
    ASSERT_TRUE(x.R == y.R && x.t == y.t && x.kappa == y.kappa && x.tau == y.tau)
        << "values of measurement " << k;
  }
  ASSERT_EQ(a.initial.size(), b.initial.size());
  for (std::size_t k = 0; k < a.initial.size(); ++k)
    ASSERT_TRUE(a.initial[k].R == b.initial[k].R && a.initial[k].t == b.initial[k].t);
}

TEST(DdsRobotFiles, EachRobotsFileIsItsShareOfTheWholeFile) {
  for (const char* kind : {"city", "grid3d"}) {
    const std::string dir = temp_dir();
    const PoseGraph g = read_g2o(generate_split(dir, kind, 203, 4));
    for (std::uint32_t r = 0; r < 4; ++r) {
      const std::string path = dir + "/robots/robot" + std::to_string(r) + ".g2o";
      ASSERT_TRUE(agent::is_robot_file(path));
      agent::RobotShare own = agent::read_robot_file(path, r);
      EXPECT_EQ(own.num_poses, 0u) << "n is not in a robot's file";
      agent::adopt_num_poses(own, g.num_poses, path);
      expect_same_share(own, agent::robot_share(g, r, 4));
    }
    EXPECT_FALSE(agent::is_robot_file(dir + "/whole.g2o"));
  }
}

TEST(DdsRobotFiles, WithoutIndexOrVerticesTheConventionStillHolds) {
  const std::string dir = temp_dir();
  const PoseGraph g = read_g2o(generate_split(dir, "city", 100, 2, true));
  const std::string path = dir + "/robots/robot1.g2o";
  // Drop the index line: positions become (robot << 40) + line order.
  std::istringstream in(slurp(path));
  {
    std::ofstream o(path);
    for (std::string line; std::getline(in, line);)
      if (line.rfind("# tessera-measurement-index", 0) != 0) o << line << "\n";
  }
  agent::RobotShare own = agent::read_robot_file(path, 1);
  const agent::RobotShare ref = agent::robot_share(g, 1, 2);
  EXPECT_TRUE(own.initial.empty());
  ASSERT_EQ(own.measurements.size(), ref.measurements.size());
  for (std::size_t k = 0; k < own.measurements.size(); ++k) {
    EXPECT_EQ(own.measurement_index[k], (std::uint64_t{1} << 40) + k);
    EXPECT_EQ(own.measurements[k].i, ref.measurements[k].i);
  }
  EXPECT_THROW(agent::adopt_num_poses(own, 60, path), InputError);  // poses beyond n
}

// The fork server's graph cache (core/runtime/preloaded_graph.hpp): the same graph as reading the
// file, only for that exact path, and nothing kept (no throw) for a robot file or a file
// that does not parse, which each agent then reads itself and reports.
TEST(DdsRobotFiles, PreloadedGraphIsTheFilesGraphForThatPathOnly) {
  const std::string dir = temp_dir();
  const std::string whole = generate_split(dir, "city", 120, 3);
  agent::preload_graph(whole);
  const PoseGraph* pre = agent::preloaded_graph(whole);
  ASSERT_NE(pre, nullptr);
  const PoseGraph g = read_g2o(whole);
  for (std::uint32_t r = 0; r < 3; ++r)
    expect_same_share(agent::robot_share(*pre, r, 3), agent::robot_share(g, r, 3));
  EXPECT_EQ(agent::preloaded_graph(dir + "/robots/robot0.g2o"), nullptr);
  EXPECT_EQ(agent::preloaded_graph(dir + "/./whole.g2o"), nullptr) << "exact path only";

  const std::string bad = dir + "/bad.g2o";
  std::ofstream(bad) << "VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 7 1 0 0 1 0 0 1 0 1\nnonsense\n";
  EXPECT_NO_THROW(agent::preload_graph(bad));
  EXPECT_EQ(agent::preloaded_graph(bad), nullptr);
  EXPECT_EQ(agent::preloaded_graph(whole), nullptr) << "a failed preload keeps nothing";
  EXPECT_THROW(read_g2o(bad), InputError) << "the agent's own read still reports it";

  agent::preload_graph(dir + "/robots/robot1.g2o");
  EXPECT_EQ(agent::preloaded_graph(dir + "/robots/robot1.g2o"), nullptr)
      << "robot files are not cached";
}

TEST(DdsRobotFiles, BadRobotFilesNameTheFileAndLine) {
  const std::string dir = temp_dir();
  auto write = [&](const std::string& text) {
    const std::string p = dir + "/bad.g2o";
    std::ofstream(p) << text;
    return p;
  };
  auto message = [](const std::string& p) {
    try {
      agent::read_robot_file(p, 0);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string edge = " 1 0 0 1 0 0 1 0 1\n";
  std::string p = write("# tessera-robot poses 2 4\nEDGE_SE2 2 3" + edge + "EDGE_SE2 0 1" + edge);
  EXPECT_NE(message(p).find("bad.g2o:3"), std::string::npos) << message(p);
  EXPECT_NE(message(p).find("touches none of this robot's poses 2..3"), std::string::npos);
  p = write("# tessera-robot poses 2 5\nEDGE_SE2 2 3" + edge);
  EXPECT_NE(message(p).find("pose 4 of this robot appears on no line"), std::string::npos)
      << message(p);
  p = write("# tessera-robot poses 2\n");
  EXPECT_NE(message(p).find("expected '# tessera-robot poses BEGIN END'"), std::string::npos);
  p = write("# tessera-robot poses 0 2\n# tessera-measurement-index 4 5\nEDGE_SE2 0 1" + edge);
  EXPECT_NE(message(p).find("lists 2 positions for 1 EDGE lines"), std::string::npos) << message(p);
  p = write(
      "# tessera-robot poses 0 2\n# tessera-measurement-index 4\n# tessera-known-inliers 5\n"
      "EDGE_SE2 0 1" +
      edge);
  EXPECT_NE(message(p).find("bad.g2o:3"), std::string::npos) << message(p);
  EXPECT_NE(message(p).find("names measurement 5, which is not one of this file's EDGE lines"),
            std::string::npos)
      << message(p);
}

// A robot file's '# tessera-known-inliers' line (a dpgo CSV's is_known_inlier column) gives the
// share the file positions of its flagged measurements.
TEST(DdsRobotFiles, KnownInlierFlagsTravelInTheRobotFile) {
  const std::string dir = temp_dir();
  const std::string p = dir + "/robot0.g2o";
  const std::string edge = " 1 0 0 1 0 0 1 0 1\n";
  std::ofstream(p) << "# tessera-robot poses 0 3\n# tessera-measurement-index 2 7 9\n"
                      "# tessera-known-inliers 9 2\n"
                      "EDGE_SE2 0 1" +
                          edge + "EDGE_SE2 1 2" + edge + "EDGE_SE2 2 5" + edge;
  const agent::RobotShare s = agent::read_robot_file(p, 0);
  EXPECT_EQ(s.known_inlier_index, (std::vector<std::uint64_t>{2, 9}));
}

// The agents read their own files; the coordinator learns n from their ranges.
TEST(DdsRobotFiles, DdsRunFromPerRobotFilesEqualsTheSingleFile) {
  const std::string dir = temp_dir();
  const int N = 3, domain = 203;
  const std::string whole = generate_split(dir, "grid3d", 240, N, true);
  const std::string run = "robots-" + std::to_string(getpid());
  std::vector<Process> procs;
  procs.reserve(N + 1);
  procs.push_back(
      start({bin("tessera-coordinator"), "--agents", std::to_string(N), "--run-id", run, "--domain",
             std::to_string(domain), "--timeout", "20", "--run-timeout", "60", "--summary",
             dir + "/summary.json", "--init", "distributed", "--partition", "highest"},
            dir + "/coordinator.log"));
  for (int k = 0; k < N; ++k)
    procs.push_back(
        start({bin("tessera-agent"), "--graph", dir + "/robots/robot" + std::to_string(k) + ".g2o",
               "--robots", std::to_string(N), "--id", std::to_string(k), "--run-id", run,
               "--domain", std::to_string(domain), "--timeout", "20"},
              dir + "/agent" + std::to_string(k) + ".log"));
  std::vector<Process*> all;
  for (auto& p : procs) all.push_back(&p);
  ASSERT_TRUE(wait_all(all, 90)) << "a process hung";
  for (Process* p : all) ASSERT_EQ(p->exit_code, 0) << p->output();
  const std::string summary = slurp(dir + "/summary.json");

  // The single file, in process (the DDS run from the single file gives the same iterates:
  // dds_initialization_test).
  const PoseGraph g = read_g2o(whole);
  PartitionOptions popt;
  popt.parts = N;
  popt.preset = parse_preset("highest");
  popt.objective = PartitionObjective::kRounds;  // solve's and the coordinator's default
  const std::vector<int> part =
      partition_graph(graph_structure_from_pose_graph(g), popt).assignment;
  DistributedOptions opt;
  opt.initialization = DistributedInit::kDistributed;
  const DistributedResult ref = solve_distributed(g, part, opt);
  EXPECT_EQ(json_field(summary, "num_poses"), static_cast<double>(g.num_poses)) << summary;
  EXPECT_EQ(json_field(summary, "rounds"), ref.rounds) << summary;
  EXPECT_NEAR(json_field(summary, "cost"), ref.cost, 1e-9 * ref.cost) << summary;
  EXPECT_NEAR(json_field(summary, "grad_norm"), ref.grad_norm, 1e-9 * ref.grad_norm) << summary;
}

// `tessera launch DIR` runs one agent per file and agrees with `tessera solve` on the whole file.
TEST(DdsRobotFiles, LaunchOnAFolderOfRobotFilesAgreesWithSolve) {
  const std::string dir = temp_dir();
  const std::string whole = generate_split(dir, "city", 200, 3);
  std::string out;
  // The preset is explicit: launch's and solve's default presets need not be the same.
  ASSERT_EQ(
      run_command(bin("tessera") + " launch " + dir +
                      "/robots --partition eco --domain 204 --quiet --json " + dir + "/launch.json",
                  &out),
      0)
      << out;
  ASSERT_EQ(run_command(bin("tessera") + " solve " + whole +
                            " --algorithm irbcd --agents 3 --partition eco --certify --json " +
                            dir + "/solve.json",  // launch certifies by default
                        &out),
            0)
      << out;
  const std::string l = slurp(dir + "/launch.json"), s = slurp(dir + "/solve.json");
  EXPECT_EQ(json_field(l, "agents"), 3) << l;
  EXPECT_EQ(json_field(l, "rounds"), json_field(s, "rounds")) << l << s;
  EXPECT_NEAR(json_field(l, "cost"), json_field(s, "cost"), 1e-9 * json_field(s, "cost")) << l << s;
}

}  // namespace
}  // namespace tessera::test::dds
