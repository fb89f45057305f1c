// The synthetic multi-robot generator and `tessera generate`.
#include <Eigen/LU>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/graph/connectivity.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <vector>

#include "test_support.hpp"

namespace tessera {
namespace {

const TrajectoryKind kAllKinds[] = {TrajectoryKind::kGrid3d, TrajectoryKind::kSphere,
                                    TrajectoryKind::kTorus, TrajectoryKind::kCity};

GeneratorOptions options_for(TrajectoryKind kind, std::size_t n, std::size_t robots,
                             std::uint64_t seed = 1) {
  GeneratorOptions o;
  o.kind = kind;
  o.num_poses = n;
  o.num_robots = robots;
  o.seed = seed;
  return o;
}

// kappa ||R_j - R_i R_ij||_F^2 + tau ||t_j - t_i - R_i t_ij||^2, computed here on purpose
// (independently of the library's objective).
double edge_residual(const Measurement& m, const std::vector<Pose>& x) {
  const Pose &a = x[m.i], &b = x[m.j];
  return m.kappa * (b.R - a.R * m.R).squaredNorm() + m.tau * (b.t - a.t - a.R * m.t).squaredNorm();
}

// A graph with the given noise (rotation rad, translation m); every other option as options_for.
GeneratorResult generate_with_noise(TrajectoryKind kind, std::size_t n, std::size_t robots,
                                    double rotation_noise, double translation_noise) {
  GeneratorOptions o = options_for(kind, n, robots);
  o.rotation_noise = rotation_noise;
  o.translation_noise = translation_noise;
  return generate_pose_graph(o);
}

// The cost of the generated graph at its ground truth (sum of edge_residual).
double residual_at_truth(const GeneratorResult& r) {
  double f = 0;
  for (const auto& m : r.graph.measurements) f += edge_residual(m, r.ground_truth);
  return f;
}

TEST(Generator, SameSeedSameBytesOtherSeedOtherGraph) {
  const std::string dir = test::temp_dir();
  for (TrajectoryKind kind : kAllKinds) {
    SCOPED_TRACE(trajectory_kind_name(kind));
    write_g2o(generate_pose_graph(options_for(kind, 300, 3, 5)).graph, dir + "/a.g2o");
    write_g2o(generate_pose_graph(options_for(kind, 300, 3, 5)).graph, dir + "/b.g2o");
    write_g2o(generate_pose_graph(options_for(kind, 300, 3, 6)).graph, dir + "/c.g2o");
    const std::string a = test::read_text_file(dir + "/a.g2o");
    EXPECT_GT(a.size(), 1000u);
    EXPECT_EQ(a, test::read_text_file(dir + "/b.g2o"));
    EXPECT_NE(a, test::read_text_file(dir + "/c.g2o"));
  }
}

TEST(Generator, CountsRobotRangesAndConnectivity) {
  for (TrajectoryKind kind : kAllKinds) {
    for (std::size_t n : {2, 3, 10, 37, 500}) {
      for (std::size_t robots : {1, 2, 7}) {
        if (robots > n) continue;
        SCOPED_TRACE(std::string(trajectory_kind_name(kind)) + " n=" + std::to_string(n) +
                     " robots=" + std::to_string(robots));
        const GeneratorResult r = generate_pose_graph(options_for(kind, n, robots));
        const PoseGraph& g = r.graph;
        EXPECT_EQ(g.d, kind == TrajectoryKind::kCity ? 2 : 3);
        ASSERT_EQ(g.num_poses, n);
        ASSERT_EQ(r.ground_truth.size(), n);
        ASSERT_EQ(g.initial.size(), n);
        ASSERT_EQ(r.robot_of.size(), n);
        EXPECT_EQ(r.odometry_edges, n - robots);
        EXPECT_EQ(r.rendezvous_edges, robots - 1);
        EXPECT_EQ(g.num_measurements(), r.odometry_edges + r.rendezvous_edges +
                                            r.intra_robot_closures + r.inter_robot_closures);
        EXPECT_EQ(count_components(g), 1u);

        // Robot r owns [r n / N, (r + 1) n / N): non-empty, contiguous, in order.
        for (std::size_t k = 0; k < n; ++k) {
          const std::size_t robot = r.robot_of[k];
          EXPECT_LE(robot * n / robots, k);
          EXPECT_LT(k, (robot + 1) * n / robots);
        }
        std::size_t intra = 0, inter = 0;
        std::set<std::pair<std::size_t, std::size_t>> pairs;
        for (std::size_t e = 0; e < g.num_measurements(); ++e) {
          const Measurement& m = g.measurements[e];
          ASSERT_LT(m.i, m.j);
          ASSERT_LT(m.j, n);
          EXPECT_TRUE(pairs.insert({m.i, m.j}).second) << "duplicate edge " << m.i << "-" << m.j;
          if (e + 1 < n) {
            EXPECT_EQ(m.i, e);  // the chain comes first, in id order
            EXPECT_EQ(m.j, e + 1);
          } else {
            EXPECT_GE(m.j - m.i, 2u) << "closures never repeat an odometry step";
            (r.robot_of[m.i] == r.robot_of[m.j] ? intra : inter)++;
          }
        }
        EXPECT_EQ(intra, r.intra_robot_closures);
        EXPECT_EQ(inter, r.inter_robot_closures);
      }
    }
  }
}

TEST(Generator, EveryKindHasLoopClosuresOfBothClasses) {
  for (TrajectoryKind kind : kAllKinds) {
    SCOPED_TRACE(trajectory_kind_name(kind));
    const GeneratorResult r = generate_pose_graph(options_for(kind, 2000, 4));
    // Literature graphs have roughly as many closures as poses; stay in that ballpark.
    EXPECT_GT(r.intra_robot_closures, 100u);
    EXPECT_GT(r.inter_robot_closures, 20u);
    EXPECT_LT(r.loop_closures(), 2000u * 2);
  }
}

TEST(Generator, ClosureProbabilityAndCap) {
  GeneratorOptions o = options_for(TrajectoryKind::kGrid3d, 1000, 3);
  o.loop_closure_probability = 0;
  o.inter_robot_closure_probability = 0;
  GeneratorResult none = generate_pose_graph(o);
  EXPECT_EQ(none.graph.num_measurements(), 999u);  // chain only
  EXPECT_EQ(count_components(none.graph), 1u);
  EXPECT_EQ(none.loop_closures(), 2u);  // the two rendezvous links

  o.loop_closure_probability = 1;
  o.inter_robot_closure_probability = 1;
  const GeneratorResult all = generate_pose_graph(o);
  // A 10x10x10 lattice has 2700 neighbour pairs, 999 of them on the path.
  EXPECT_EQ(all.graph.num_measurements(), 2700u);

  o.max_loop_closures = 25;
  const GeneratorResult capped = generate_pose_graph(o);
  EXPECT_EQ(capped.intra_robot_closures + capped.inter_robot_closures, 25u);
  EXPECT_EQ(capped.graph.num_measurements(), 999u + 25u);
}

TEST(Generator, NoiseFreeGraphHasZeroResidualAtTheTruthAndExactInitialGuess) {
  for (TrajectoryKind kind : kAllKinds) {
    SCOPED_TRACE(trajectory_kind_name(kind));
    const std::size_t n = 400;
    const GeneratorResult r = generate_with_noise(kind, n, 3, 0, 0);
    for (const auto& m : r.graph.measurements) {
      EXPECT_TRUE(std::isfinite(m.kappa) && m.kappa > 0);
      EXPECT_TRUE(std::isfinite(m.tau) && m.tau > 0);
    }
    EXPECT_LT(residual_at_truth(r), 1e-18);
    for (std::size_t k = 0; k < n; ++k) {
      EXPECT_LT((r.graph.initial[k].t - r.ground_truth[k].t).norm(), 1e-9);
      EXPECT_LT((r.graph.initial[k].R - r.ground_truth[k].R).norm(), 1e-9);
    }
  }
}

TEST(Generator, GroundTruthIsRigidAndStepsAreAboutOneMetre) {
  for (TrajectoryKind kind : kAllKinds) {
    SCOPED_TRACE(trajectory_kind_name(kind));
    const GeneratorResult r = generate_pose_graph(options_for(kind, 1500, 1));
    const int d = r.graph.d;
    for (std::size_t k = 0; k < r.ground_truth.size(); ++k) {
      const Pose& p = r.ground_truth[k];
      EXPECT_LT((p.R.transpose() * p.R - Eigen::MatrixXd::Identity(d, d)).norm(), 1e-12);
      EXPECT_NEAR(p.R.determinant(), 1.0, 1e-12);
      if (k > 0) {
        const double step = (p.t - r.ground_truth[k - 1].t).norm();
        EXPECT_GT(step, 0.01);
        EXPECT_LT(step, 2.0);
      }
    }
  }
}

// The weights match the noise: at the truth, each edge's residual averages
// kappa * 2 E|w|^2 + tau * E|e|^2 = dof_R + d (3 in 2D, 6 in 3D).
TEST(Generator, WeightsAreConsistentWithTheNoise) {
  for (TrajectoryKind kind : kAllKinds) {
    SCOPED_TRACE(trajectory_kind_name(kind));
    const GeneratorResult r = generate_with_noise(kind, 4000, 2, 0.02, 0.1);
    const double expected = r.graph.d == 2 ? 3.0 : 6.0;
    EXPECT_NEAR(residual_at_truth(r) / double(r.graph.num_measurements()), expected,
                0.05 * expected);
    EXPECT_DOUBLE_EQ(r.graph.measurements[0].kappa, 1.0 / (2 * 0.02 * 0.02));
    EXPECT_DOUBLE_EQ(r.graph.measurements[0].tau, 1.0 / (0.1 * 0.1));
  }
}

TEST(Generator, RoundTripThroughTheG2oReader) {
  const std::string dir = test::temp_dir();
  for (TrajectoryKind kind : kAllKinds) {
    SCOPED_TRACE(trajectory_kind_name(kind));
    const GeneratorResult r = generate_pose_graph(options_for(kind, 200, 3));
    write_g2o(r.graph, dir + "/g.g2o");
    const PoseGraph back = read_g2o(dir + "/g.g2o");
    ASSERT_EQ(back.num_poses, r.graph.num_poses);
    ASSERT_EQ(back.num_measurements(), r.graph.num_measurements());
    ASSERT_EQ(back.initial.size(), r.graph.initial.size());
    for (std::size_t e = 0; e < back.num_measurements(); ++e) {
      const Measurement &a = r.graph.measurements[e], &b = back.measurements[e];
      EXPECT_EQ(a.i, b.i);
      EXPECT_EQ(a.j, b.j);
      EXPECT_EQ(a.t, b.t);
      EXPECT_LE((a.R - b.R).cwiseAbs().maxCoeff(), 4e-15);
      EXPECT_NEAR(a.kappa, b.kappa, 1e-15 * a.kappa);
      EXPECT_NEAR(a.tau, b.tau, 1e-15 * a.tau);
    }
  }
}

void expect_invalid(const GeneratorOptions& o, const std::string& message) {
  EXPECT_NE(test::input_error_of([&] { generate_pose_graph(o); }).find(message), std::string::npos)
      << message;
}

TEST(Generator, BadOptionsNameTheField) {
  GeneratorOptions o;
  o.num_poses = 0;
  expect_invalid(o, "num_poses = 0: must be in [2, 10000000]");
  o = {};
  o.num_poses = 5;
  o.num_robots = 6;
  expect_invalid(o, "num_robots = 6: must be in [1, num_poses = 5]");
  o = {};
  o.num_robots = 0;
  expect_invalid(o, "num_robots = 0");
  o = {};
  o.rotation_noise = -0.1;
  expect_invalid(o, "rotation_noise = -0.1: must be in [0, 1] rad");
  o = {};
  o.translation_noise = std::nan("");
  expect_invalid(o, "translation_noise = nan");
  o = {};
  o.loop_closure_probability = 1.5;
  expect_invalid(o, "loop_closure_probability = 1.5");
  o = {};
  o.inter_robot_closure_probability = -1;
  expect_invalid(o, "inter_robot_closure_probability = -1");
  EXPECT_EQ(test::input_error_of([] { parse_trajectory_kind("donut"); }),
            "unknown trajectory kind 'donut' (valid kinds: grid3d, sphere, torus, city)");
}

// --- the command ---

std::string tessera() {
  const std::string path = test::bin("tessera");
  EXPECT_TRUE(std::ifstream(path).good()) << path << " is not built";
  return path;
}

TEST(GenerateCommand, WritesGraphTruthAndJsonAndPrintsASummary) {
  const std::string dir = test::temp_dir();
  std::string out;
  const int rc = test::run_command(tessera() + " generate --kind sphere --poses 120 --robots 3 " +
                                       "--seed 9 --out " + dir + "/g.g2o --truth " + dir +
                                       "/t.tum --json " + dir + "/s.json",
                                   &out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("generated sphere: 120 poses, "), std::string::npos) << out;
  EXPECT_NE(out.find(" 3 robots, "), std::string::npos) << out;
  EXPECT_NE(out.find("loop closures"), std::string::npos) << out;

  const PoseGraph g = read_g2o(dir + "/g.g2o");
  EXPECT_EQ(g.num_poses, 120u);
  EXPECT_EQ(g.initial.size(), 120u);
  std::ifstream tum(dir + "/t.tum");
  std::size_t lines = 0;
  for (std::string line; std::getline(tum, line); ++lines) {
    std::istringstream fields(line);
    double x, count = 0, first = -1;
    while (fields >> x) first = count++ == 0 ? x : first;
    EXPECT_EQ(count, 8);
    EXPECT_EQ(first, double(lines));
  }
  EXPECT_EQ(lines, 120u);
  const std::string json = test::read_text_file(dir + "/s.json");
  EXPECT_NE(json.find("\"poses\": 120,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"edges\": " + std::to_string(g.num_measurements()) + ","),
            std::string::npos)
      << json;
  EXPECT_NE(json.find("\"kind\": \"sphere\""), std::string::npos) << json;
}

// The centralized solver certifies what the generator writes (its own tests go further).
TEST(GenerateCommand, GeneratedGraphsAreSolvedAndCertified) {
  const std::string dir = test::temp_dir();
  for (const char* kind : {"grid3d", "sphere", "torus", "city"}) {
    SCOPED_TRACE(kind);
    std::string out;
    ASSERT_EQ(test::run_command(tessera() + " generate --kind " + kind +
                                    " --poses 300 --robots 3 --seed 2 --out " + dir + "/g.g2o",
                                &out),
              0)
        << out;
    ASSERT_EQ(test::run_command(tessera() + " solve " + dir + "/g.g2o --algorithm centralized " +
                                    "--json " + dir + "/s.json",
                                &out),
              0)
        << out;
    const std::string json = test::read_text_file(dir + "/s.json");
    EXPECT_NE(json.find("\"certified\": true"), std::string::npos) << json;
  }
}

TEST(GenerateCommand, SameCommandSameBytes) {
  const std::string dir = test::temp_dir();
  const std::string args = " generate --kind city --poses 300 --robots 2 --seed 4 --out ";
  ASSERT_EQ(test::run_command(tessera() + args + dir + "/a.g2o", nullptr), 0);
  ASSERT_EQ(test::run_command(tessera() + args + dir + "/b.g2o", nullptr), 0);
  EXPECT_EQ(test::read_text_file(dir + "/a.g2o"), test::read_text_file(dir + "/b.g2o"));
  EXPECT_EQ(test::read_text_file(dir + "/a.g2o").rfind("VERTEX_SE2 0 ", 0), 0u);
}

TEST(GenerateCommand, HelpAndBadInput) {
  std::string out;
  EXPECT_EQ(test::run_command(tessera() + " generate --help", &out), 0);
  EXPECT_NE(out.find("--kind KIND"), std::string::npos) << out;
  EXPECT_NE(out.find("--loop-closures P"), std::string::npos) << out;

  const std::string dir = test::temp_dir();
  const std::string base = tessera() + " generate --out " + dir + "/x.g2o";
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {" --poses 0", "num_poses = 0: must be in [2, 10000000]"},
      {" --poses 5 --robots 6", "num_robots = 6: must be in [1, num_poses = 5]"},
      {" --rot-noise -0.5", "rotation_noise = -0.5"},
      {" --trans-noise -1", "translation_noise = -1"},
      {" --kind donut", "unknown trajectory kind 'donut'"},
      {" --poses -3", "option --poses: must not be negative"},
      {" --poses many", "option --poses: 'many' is not an integer"},
      {" --frobnicate 1", "unknown option --frobnicate"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(test::run_command(base + c.args, &out), 2) << c.args << ": " << out;
    EXPECT_NE(out.find(c.message), std::string::npos) << c.args << ": " << out;
  }
  EXPECT_EQ(test::run_command(tessera() + " generate --poses 10", &out), 2);
  EXPECT_NE(out.find("--out FILE.g2o is required"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(tessera() + " generate --out /nonexistent-dir/g.g2o", &out), 2);
  EXPECT_NE(out.find("/nonexistent-dir/g.g2o: cannot open for writing"), std::string::npos) << out;
}

}  // namespace
}  // namespace tessera
