#pragma once
// The end-of-run check shared by the permanent-loss tests (coordinator + agents started
// directly, and through `tessera launch`): nothing was lost with the dead agent.

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <tessera/io/g2o_reader.hpp>
#include <tessera/solvers/centralized_solver.hpp>

#include "dds_process_support.hpp"

namespace tessera::test::dds {

/// Expects DIR/merged.g2o to hold every pose of GRAPH (ids 0..n-1) and DIR/summary.json's
/// cost to be within 1e-6 of the centralized optimum. Returns the summary for further checks.
inline std::string expect_every_pose_at_the_optimum(const std::string& graph,
                                                    const std::string& dir) {
  const PoseGraph g = read_g2o(graph);
  const std::set<long> ids = vertex_ids(dir + "/merged.g2o");
  EXPECT_EQ(ids.size(), g.num_poses);
  EXPECT_EQ(ids.empty() ? -1L : *ids.rbegin(), static_cast<long>(g.num_poses) - 1);
  const double fstar = solve_centralized(g).cost;
  const std::string summary = slurp(dir + "/summary.json");
  const double cost = json_field(summary, "cost");
  EXPECT_LE(std::abs(cost - fstar), 1e-6 * fstar) << summary << "\nf* = " << fstar;
  return summary;
}

}  // namespace tessera::test::dds
