// `tessera launch` with the chordal start (launch's default): agent 0 solves it from the fork
// server's parsed file while the processes discover each other (runtime/early_chordal.hpp),
// and the run is the in-process engine's: same rounds, same cost. Without the fork server
// there is no parsed file and the start is solved in the initialisation stage, as before.
// Domains used here: 153, 154 (each test its own, so ctest -j is safe).

#include <gtest/gtest.h>

#include <string>

#include "dds_process_support.hpp"

namespace tessera::test::dds {
namespace {

void expect_chordal_launch_gives_the_in_process_iterates(const std::string& extra, int domain,
                                                         bool early) {
  const std::string dir = temp_dir();
  const std::string graph =
      generate_graph(dir + "/graph.g2o", "--kind grid3d --poses 300 --robots 3 --seed 11");
  const std::string solver = " --agents 3 --algorithm irbcd --partition eco --seed 7";
  const std::string ip = solve_summary(dir, graph, solver, "ip");
  ASSERT_FALSE(::testing::Test::HasFailure());
  ASSERT_GT(json_field(ip, "rounds"), 1) << "the graph should need a few rounds";
  std::string out;
  ASSERT_EQ(run_command(bin("tessera") + " launch " + graph + solver + " --domain " +
                            std::to_string(domain) + " --timeout 90 --json " + dir + "/dds.json " +
                            extra + " 2>&1",
                        &out),
            0)
      << out;
  const std::string dds = slurp(dir + "/dds.json");
  EXPECT_NE(dds.find(std::string("\"init_early\": ") + (early ? "true" : "false")),
            std::string::npos)
      << dds;
  EXPECT_GE(json_field(dds, "init_ms"), 0.0) << dds;
  EXPECT_GT(json_field(dds, "handoff_ms"), 0.0) << dds;
  EXPECT_EQ(json_field(dds, "rounds"), json_field(ip, "rounds")) << dds << ip;
  const double cost = json_field(ip, "cost");
  EXPECT_NEAR(json_field(dds, "cost"), cost, 1e-9 * cost) << dds << ip;
}

TEST(DdsEarlyChordal, AgentZeroSolvesTheStartWhileTheRunStartsWithTheSameIterates) {
  expect_chordal_launch_gives_the_in_process_iterates("", 153, true);
}

TEST(DdsEarlyChordal, WithoutTheForkServerTheStageSolvesItWithTheSameIterates) {
  expect_chordal_launch_gives_the_in_process_iterates("--no-fork-server", 154, false);
}

}  // namespace
}  // namespace tessera::test::dds
