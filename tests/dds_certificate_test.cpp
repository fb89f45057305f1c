// Distributed certification over DDS: the agents' certified sequence (solve -> certify ->
// escape -> solve ...) gives the in-process engine's results, and `tessera launch` certifies by
// default and reports the certificate in its JSON summary.
// Domains used here: 171-173, 125 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <tessera/certification/dual_bound.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <vector>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

TEST(DdsCertificate, StaircaseOverDdsGivesTheInProcessResult) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/city.g2o";
  // Large rotation noise and rank 2 = d: the first certificate fails, the staircase climbs.
  generate_graph(graph,
                 "--kind city --poses 120 --robots 3 --rot-noise 0.5 --trans-noise 0.3 --seed 1");
  ASSERT_FALSE(::testing::Test::HasFailure());
  const int agents = 3, domain = 171;
  const std::string run = "cert-" + std::to_string(getpid());
  const auto [summary, assignment] = run_and_read(
      dir, graph, agents, run, domain,
      {"--timeout", "20", "--run-timeout", "90", "--partition", "eco", "--rank", "2", "--certify",
       "--init", "file"},  // the in-process reference starts from the file's poses too
      90);
  ASSERT_FALSE(::testing::Test::HasFailure());

  const PoseGraph g = read_g2o(graph);
  ASSERT_EQ(assignment.size(), g.num_poses);
  DistributedOptions opt;
  opt.rank = 2;
  opt.certify = true;
  const DistributedResult ref = solve_distributed(g, assignment, opt, g.initial);
  ASSERT_TRUE(ref.certified.has_value());
  ASSERT_TRUE(ref.certificates.back().result.certified);
  ASSERT_FALSE(ref.escapes.empty()) << "the graph should need the staircase";

  // Same verdict on the estimate as in process (the relaxation's certificate and the rounding
  // gap rule: rounding_gap_test).
  EXPECT_EQ(json_text(summary, "certified"), *ref.certified ? "true" : "false") << summary;
  EXPECT_EQ(json_number(summary, "final_rank"), ref.final_rank) << summary;
  EXPECT_EQ(json_number(summary, "certificate_rounds"), ref.certificate_rounds) << summary;
  EXPECT_EQ(json_number(summary, "escape_rounds"), ref.escape_rounds) << summary;
  EXPECT_EQ(json_number(summary, "certificate_bytes"), static_cast<double>(ref.certificate_bytes));
  EXPECT_EQ(json_number(summary, "rounds"), ref.rounds) << summary;
  EXPECT_NEAR(json_number(summary, "min_eigenvalue"), ref.min_eigenvalue,
              1e-9 * std::abs(ref.min_eigenvalue) + 1e-15);
  EXPECT_NEAR(json_number(summary, "cost"), ref.cost, 1e-9 * ref.cost) << summary;
}

TEST(DdsCertificate, LaunchCertifiesByDefaultAndReportsIt) {
  const std::string dir = temp_dir();
  std::string out;
  const int rc = run_command(bin("tessera") + " launch --agents 3 --poses 150 --domain 172 " +
                                 "--partition eco --timeout 60 --json " + dir + "/s.json 2>&1",
                             &out);
  ASSERT_EQ(rc, 0) << out;
  const std::string json = slurp(dir + "/s.json");
  EXPECT_EQ(json_text(json, "certified"), "true") << json;
  for (const char* field :
       {"min_eigenvalue", "certificate_rounds", "final_rank", "certificate_bytes"})
    EXPECT_FALSE(std::isnan(json_number(json, field))) << field << json;
  EXPECT_GT(json_number(json, "certificate_rounds"), 0);
  EXPECT_GT(json_number(json, "certificate_bytes"), 0);
  EXPECT_EQ(json_number(json, "final_rank"), 5);

  const int rc2 = run_command(bin("tessera") + " launch --agents 2 --poses 100 --domain 173 " +
                                  "--no-certify --timeout 60 --json " + dir + "/n.json 2>&1",
                              &out);
  ASSERT_EQ(rc2, 0) << out;
  const std::string plain = slurp(dir + "/n.json");
  EXPECT_EQ(json_text(plain, "certified"), "null") << plain;
}

// The certificate's weak-duality bound (dual_bound.hpp) over DDS: the coordinator's summary
// reports the lower bound the agents proved, the same as in process.
TEST(DdsCertificate, TheProvedLowerBoundIsTheInProcessOne) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/grid.g2o";
  generate_graph(graph, "--kind grid3d --poses 125 --robots 3 --seed 3");
  ASSERT_FALSE(::testing::Test::HasFailure());
  const int agents = 3, domain = 125;
  const std::string run = "bound-" + std::to_string(getpid());
  const auto [summary, assignment] =
      run_and_read(dir, graph, agents, run, domain,
                   {"--timeout", "20", "--run-timeout", "90", "--partition", "eco", "--certify",
                    "--init", "file"},
                   90);
  ASSERT_FALSE(::testing::Test::HasFailure());

  const PoseGraph g = read_g2o(graph);
  DistributedOptions opt;
  opt.certify = true;
  const DistributedResult ref = solve_distributed(g, assignment, opt, g.initial);
  ASSERT_TRUE(ref.certified.value_or(false));
  ASSERT_TRUE(ref.certificates.back().result.interface_test);
  const DualBound& b = ref.certificate_bound;
  ASSERT_TRUE(b.proved());
  EXPECT_EQ(json_text(summary, "certified"), "true") << summary;
  const double f = std::abs(b.relaxation_cost);
  EXPECT_NEAR(json_number(summary, "dual_lower_bound"), b.lower_bound, 1e-9 * f) << summary;
  EXPECT_NEAR(json_number(summary, "certificate_shift"), b.shift, 1e-12 * b.shift) << summary;
  EXPECT_NEAR(json_number(summary, "certificate_grad_norm"), b.gradient_norm,
              1e-6 * b.gradient_norm + 1e-12)
      << summary;
  EXPECT_NEAR(json_number(summary, "suboptimality_bound"), ref.cost - b.lower_bound, 1e-9 * f);
  EXPECT_LE(json_number(summary, "relaxation_suboptimality_bound"),
            kDefaultSuboptimalityTolerance * std::max(1.0, f))
      << summary;
}

}  // namespace
}  // namespace tessera::test::dds
