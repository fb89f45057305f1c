// The Newton refinement over DDS: agents started with `--refine newton` through the coordinator
// take the in-process engine's iterates (same rounds, same refined cost), and `tessera launch
// --refine newton` forwards the option and ends at the optimum; `--refine auto` refines this
// chain too (its rounds stop short), as the in-process engine does.
// Domains used here: 80-81, 99 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <regex>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <vector>

#include "dds_process_support.hpp"
#include "refine_harness.hpp"

namespace tessera::test::dds {
namespace {

// A chain-like generated graph: a lawnmower path with 4 loop closures, where the rounds stop
// ~1e-5 above f* at gradient 0.01.
const char* kChain =
    "--kind grid3d --poses 600 --max-loop-closures 4 --rot-noise 0.1 --trans-noise 1 --seed 3";

// `tessera launch` of the chain with `refine` (a --refine value) on `domain`: it ends certified
// at f* (to round-off) and agent 0 reported the refinement (as it reports the certificate: at
// its start, then every 2 s). Returns the chain's file.
std::string expect_launch_refines_to_the_optimum(const std::string& refine, int domain) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/chain.g2o";
  generate_graph(graph, kChain);
  if (::testing::Test::HasFailure()) return graph;
  std::string out;
  const int rc = run_command(bin("tessera") + " launch " + graph + " --agents 3 --domain " +
                                 std::to_string(domain) + " --refine " + refine +
                                 " --timeout 90 --json " + dir + "/s.json 2>&1",
                             &out);
  EXPECT_EQ(rc, 0) << out;
  if (rc != 0) return graph;
  EXPECT_NE(out.find("refinement: Newton step 1, CG iteration "), std::string::npos) << out;
  const std::string json = slurp(dir + "/s.json");
  EXPECT_EQ(json_text(json, "certified"), "true") << json;
  const double fstar = tight_optimum(read_g2o(graph));
  EXPECT_NEAR(json_number(json, "cost"), fstar, 1e-8 * fstar) << json;
  return graph;
}

TEST(DdsNewtonRefine, AgentsOverDdsTakeTheInProcessIterates) {
  const std::string dir = temp_dir();
  const std::string graph = dir + "/chain.g2o";
  generate_graph(graph, kChain);
  ASSERT_FALSE(::testing::Test::HasFailure());
  const int agents = 3, domain = 80;
  const std::string run = "refine-" + std::to_string(getpid());
  const auto [summary, assignment] =
      run_and_read(dir, graph, agents, run, domain,
                   {"--timeout", "20", "--run-timeout", "90", "--partition", "eco", "--refine",
                    "newton", "--init", "file"},
                   90);
  ASSERT_FALSE(::testing::Test::HasFailure());

  const PoseGraph g = read_g2o(graph);
  ASSERT_EQ(assignment.size(), g.num_poses);
  DistributedOptions opt;
  set_refine_mode(opt.refine, "newton");
  const DistributedResult ref = solve_distributed(g, assignment, opt, g.initial);
  ASSERT_EQ(ref.refines.size(), 1u);
  ASSERT_GE(ref.refines[0].accepted_steps, 1);
  // The refinement's default preconditioner on this chain: exact solves through the interface
  // (every agent factors the same interface matrix from the shares it receives over DDS).
  EXPECT_GE(ref.refines[0].interface_factorizations, 1);
  EXPECT_EQ(json_number(summary, "rounds"), ref.rounds) << summary;
  // The refined point (its gradient norm, summed in agent-id order as in process) and its
  // rounding (the DDS agents' distributed rounding: equal up to summation order).
  EXPECT_NEAR(json_number(summary, "grad_norm"), ref.grad_norm, 1e-9 * ref.grad_norm) << summary;
  EXPECT_NEAR(json_number(summary, "cost"), ref.cost, 1e-9 * ref.cost) << summary;
  // And that is the optimum, which the rounds alone do not reach on this chain.
  const double fstar = tight_optimum(g);
  EXPECT_NEAR(json_number(summary, "cost"), fstar, 1e-8 * fstar) << summary;
}

TEST(DdsNewtonRefine, LaunchForwardsRefineAndEndsCertifiedAtTheOptimum) {
  expect_launch_refines_to_the_optimum("newton", 81);
}

TEST(DdsNewtonRefine, LaunchForwardsRefineAutoWhichRefinesAChainWhoseRoundsStopShort) {
  const std::string graph = expect_launch_refines_to_the_optimum("auto", 99);
  // A value launch does not know is refused by name.
  std::string bad;
  EXPECT_EQ(run_command(bin("tessera") + " launch " + graph + " --refine sometimes 2>&1", &bad), 2);
  EXPECT_NE(bad.find("--refine"), std::string::npos) << bad;
}

}  // namespace
}  // namespace tessera::test::dds
