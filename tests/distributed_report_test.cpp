// DistributedResult::full_report(): the report of an in-process distributed solve names what
// the result holds (agents, rounds, stop reason, cost, certificate).

#include <gtest/gtest.h>

#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <vector>

#include "random_graph.hpp"

namespace tessera {
namespace {

TEST(DistributedReport, NamesTheRunsFigures) {
  test::RandomGraphSpec spec;
  spec.poses = 24;
  spec.loop_closures = 10;
  const PoseGraph graph = test::random_pose_graph(spec);
  std::vector<int> assignment(graph.num_poses);
  for (std::size_t i = 0; i < assignment.size(); ++i)
    assignment[i] = static_cast<int>(3 * i / assignment.size());
  DistributedOptions options;
  options.certify = true;
  const DistributedResult r = solve_distributed(graph, assignment, options);
  const std::string report = r.full_report();
  EXPECT_NE(report.find("3 agents"), std::string::npos) << report;
  EXPECT_NE(report.find(std::to_string(r.rounds) + " rounds"), std::string::npos) << report;
  EXPECT_NE(report.find("stop: " + r.stop_reason), std::string::npos) << report;
  EXPECT_NE(report.find("certified: "), std::string::npos) << report;
  ASSERT_TRUE(r.certified.has_value());
  EXPECT_EQ(report.find("not checked"), std::string::npos) << report;
  EXPECT_NE(report.find(std::to_string(r.messages) + " messages"), std::string::npos) << report;
}

}  // namespace
}  // namespace tessera
