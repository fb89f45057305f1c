// The preconditioner's measurement subset: what it keeps under a flop budget, and that the
// centralized robust solve with such a preconditioner finds the same outliers and the same
// certified optimum as with the whole graph's factor, on generated graphs with many random
// wrong closures.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <tessera/generate/generator.hpp>
#include <tessera/robust/gnc_centralized.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/solvers/preconditioner_edges.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "gnc_fixtures.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

GeneratorResult grid(double outlier_fraction) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 216;
  o.num_robots = 4;
  o.seed = 7;
  o.outlier_fraction = outlier_fraction;
  o.outlier_kind = OutlierKind::kRandom;
  return generate_pose_graph(o);
}

bool is_outlier(const GeneratorResult& r, std::size_t e) {
  return std::binary_search(r.outliers.begin(), r.outliers.end(), e);
}

TEST(PreconditionerEdges, KeepsEveryMeasurementWhileTheWholeFactorFitsTheBudget) {
  const GeneratorResult dirty = grid(0.5);
  const PoseGraph& g = dirty.graph;
  const std::vector<double> ones(g.num_measurements(), 1.0);
  PreconditionerEdgeOptions o;  // default budget: far above this small graph's factor
  PreconditionerEdges edges = select_preconditioner_edges(g.d, g.num_poses, g.measurements, ones,
                                                          test::odometry_flags(g), o);
  EXPECT_TRUE(edges.all);
  EXPECT_EQ(edges.kept.size(), g.num_measurements());
  EXPECT_EQ(edges.kept_flops, edges.full_flops);
  EXPECT_EQ(edges.full_flops, predicted_factor_flops(g.d, g.num_poses, g.measurements));
  o.max_flops = 0;  // no limit, and no analysis either
  edges = select_preconditioner_edges(g.d, g.num_poses, g.measurements, ones, {}, o);
  EXPECT_TRUE(edges.all);
  EXPECT_EQ(edges.analyses, 0);
}

TEST(PreconditionerEdges, LowWeightRandomClosuresLeaveFirstAndTheFactorShrinks) {
  const GeneratorResult clean = grid(0.0);
  const GeneratorResult dirty = grid(0.5);
  const PoseGraph& g = dirty.graph;
  ASSERT_GT(dirty.outliers.size(), 50u);
  const double clean_flops = predicted_factor_flops(g.d, g.num_poses, clean.graph.measurements);
  const double full_flops = predicted_factor_flops(g.d, g.num_poses, g.measurements);
  // The wrong closures join random poses: the whole factor costs several times the clean one.
  EXPECT_GT(full_flops, 3 * clean_flops);

  // Weights as in a robust solve's later steps: the wrong closures near 0.
  std::vector<double> weights(g.num_measurements(), 1.0);
  for (std::size_t e : dirty.outliers) weights[e] = 0.05;
  const std::vector<bool> known = test::odometry_flags(g);
  PreconditionerEdgeOptions o;
  o.max_flops = clean_flops;
  const PreconditionerEdges edges =
      select_preconditioner_edges(g.d, g.num_poses, g.measurements, weights, known, o);
  EXPECT_FALSE(edges.all);
  EXPECT_LE(edges.kept_flops, o.max_flops);
  EXPECT_EQ(edges.full_flops, full_flops);
  EXPECT_TRUE(std::is_sorted(edges.kept.begin(), edges.kept.end()));
  std::size_t known_kept = 0, wrong_kept = 0, true_kept = 0;
  for (std::size_t e : edges.kept) {
    known_kept += known[e];
    wrong_kept += is_outlier(dirty, e);
    true_kept += !is_outlier(dirty, e);
  }
  EXPECT_EQ(known_kept, static_cast<std::size_t>(std::count(known.begin(), known.end(), true)));
  // Every true measurement comes before any wrong one, and the clean graph fits the budget.
  EXPECT_EQ(true_kept, clean.graph.num_measurements());
  EXPECT_LT(wrong_kept, dirty.outliers.size() / 4);
}

TEST(PreconditionerEdges, BadBudgetNamesTheField) {
  GncCentralizedOptions o;
  o.preconditioner.max_flops = -1;
  EXPECT_TRUE(test::validation_names(o, "PreconditionerEdgeOptions.max_flops"));
}

TEST(GncCentralized, ASmallPreconditionerRejectsTheSameOutliersAtTheSameCertifiedCost) {
  const GeneratorResult clean = grid(0.0);
  const GeneratorResult dirty = grid(0.5);
  GncCentralizedOptions full;
  full.robust.kind = RobustKind::kGncTls;
  full.preconditioner.max_flops = 0;  // every solve factors every measurement it has
  GncCentralizedOptions small = full;
  small.preconditioner.max_flops =
      1.2 * predicted_factor_flops(dirty.graph.d, dirty.graph.num_poses, clean.graph.measurements);

  const GncCentralizedResult a = solve_gnc_centralized(dirty.graph, full);
  const GncCentralizedResult b = solve_gnc_centralized(dirty.graph, small);
  EXPECT_EQ(a.rejected, dirty.outliers);
  EXPECT_EQ(b.rejected, a.rejected);
  EXPECT_NEAR(b.final_solve.cost, a.final_solve.cost, 1e-8 * a.final_solve.cost);
  EXPECT_TRUE(a.final_solve.certified.value_or(false));
  EXPECT_TRUE(b.final_solve.certified.value_or(false));

  // The solves that still held wrong closures factored a much smaller matrix.
  // The first solve, one per outer step, and at least one of the kept set.
  ASSERT_GE(b.solves.size(), static_cast<std::size_t>(b.outer_iterations) + 2);
  int sparsified = 0;
  for (const GncSolveWork& w : b.solves) {
    if (w.preconditioner_measurements == w.measurements) {
      EXPECT_EQ(w.preconditioner_flops, w.full_flops);
      continue;
    }
    ++sparsified;
    EXPECT_LE(w.preconditioner_flops, small.preconditioner.max_flops);
  }
  EXPECT_GT(sparsified, 0);
  // The first (plain) solve holds every wrong closure: its factor is a third of the whole one.
  EXPECT_LT(b.solves.front().preconditioner_flops, 0.4 * b.solves.front().full_flops);
  // The full preconditioner's run factors everything it solves.
  for (const GncSolveWork& w : a.solves) EXPECT_EQ(w.preconditioner_measurements, w.measurements);
}

}  // namespace
}  // namespace tessera
