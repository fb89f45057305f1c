// The coarse correction: its cost is the cut's part of f, its motions lower f by exactly the
// coarse decrease and keep the iterate on the manifold, it undoes a rigid drift of the blocks,
// and two-level rounds give the same iterates in any delivery order and fewer rounds.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/util/input_error.hpp>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "random_graph.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// Edge terms of f at the lifted X, split into the cut's part and the blocks' inside part.
void split_cost(const PoseGraph& g, const std::vector<int>& part, const Eigen::MatrixXd& X,
                double* cut, double* inside) {
  const int d = g.d;
  *cut = *inside = 0.0;
  for (const Measurement& m : g.measurements) {
    const auto Xi = X.middleCols(static_cast<Eigen::Index>((d + 1) * m.i), d + 1);
    const auto Xj = X.middleCols(static_cast<Eigen::Index>((d + 1) * m.j), d + 1);
    const double e = m.kappa * (Xj.leftCols(d) - Xi.leftCols(d) * m.R).squaredNorm() +
                     m.tau * (Xj.col(d) - Xi.col(d) - Xi.leftCols(d) * m.t).squaredNorm();
    (part[m.i] == part[m.j] ? *inside : *cut) += e;
  }
}

// Every agent's terms at the global lifted X, as the agents would send them.
std::vector<std::vector<double>> all_terms(const PoseGraph& g, const BlockLayout& layout,
                                           const Eigen::MatrixXd& X) {
  std::vector<std::vector<double>> out;
  for (int a = 0; a < layout.num_blocks; ++a) {
    const auto& owned = layout.poses[static_cast<std::size_t>(a)];
    const BlockProblem problem(g.d, owned, g.measurements);
    const CoarseTerms terms(a, g.d, layout, problem.owned(), problem.neighbors(), g.measurements);
    out.push_back(terms.compute(gather_pose_columns(X, owned, g.d),
                                gather_pose_columns(X, problem.neighbors(), g.d)));
  }
  return out;
}

CoarseResult solve_all(const BlockLayout& layout, int r,
                       const std::vector<std::vector<double>>& terms, const CoarseOptions& o) {
  std::vector<const std::vector<double>*> ptr;
  for (const auto& t : terms) ptr.push_back(&t);
  return solve_coarse(layout, r, ptr, o);
}

Eigen::MatrixXd moved(const Eigen::MatrixXd& X, int d, const std::vector<int>& part,
                      const std::vector<Eigen::MatrixXd>& motions) {
  Eigen::MatrixXd out = X;
  for (std::size_t i = 0; i < part.size(); ++i)
    apply_motion(motions[static_cast<std::size_t>(part[i])], d, out, static_cast<Eigen::Index>(i),
                 1);
  return out;
}

// Each block of X moved by its own random rotation (within the first d rows) and translation.
Eigen::MatrixXd drift_blocks(const Eigen::MatrixXd& X, int d, const std::vector<int>& part,
                             int blocks, double angle, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::vector<Eigen::MatrixXd> motions;
  const Eigen::Index r = X.rows();
  for (int b = 0; b < blocks; ++b) {
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(d, d);
    for (int i = 0; i < d; ++i)
      for (int j = i + 1; j < d; ++j) {
        W(i, j) = angle * normal(rng);
        W(j, i) = -W(i, j);
      }
    Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(r, r + 1);
    Z.leftCols(r).setIdentity();
    Z.topLeftCorner(d, d) = W.exp();
    for (int i = 0; i < d; ++i) Z(i, r) = normal(rng);
    motions.push_back(Z);
  }
  return moved(X, d, part, motions);
}

TEST(CoarseCorrection, OptionsNameTheBadField) {
  CoarseOptions o;
  o.every = 0;
  EXPECT_TRUE(test::validation_names(o, "every"));
  o = CoarseOptions();
  o.max_iterations = 0;
  EXPECT_THROW(o.validate(), InputError);
  o = CoarseOptions();
  o.rel_tol = 1.0;
  EXPECT_THROW(o.validate(), InputError);
}

TEST(CoarseCorrection, CostIsTheCutAndMotionsLowerFByExactlyTheCoarseDecrease) {
  test::RandomGraphSpec spec;
  spec.poses = 80;
  spec.loop_closures = 60;
  spec.seed = 4;
  const PoseGraph g = test::random_pose_graph(spec);
  const int r = 5;
  const std::vector<int> part = sequential_partition(g.num_poses, 5);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, part);
  const Eigen::MatrixXd X = drift_blocks(lift_poses(g.initial, r), g.d, part, 5, 0.1, 3);
  double cut = 0, inside = 0;
  split_cost(g, part, X, &cut, &inside);

  const CoarseResult c = solve_all(layout, r, all_terms(g, layout, X), CoarseOptions());
  EXPECT_NEAR(c.cost_before, cut, 1e-10 * cut);
  ASSERT_TRUE(c.moved);
  EXPECT_LT(c.cost_after, 0.5 * c.cost_before);

  const Eigen::MatrixXd Xc = moved(X, g.d, part, c.motions);
  double cut_after = 0, inside_after = 0;
  split_cost(g, part, Xc, &cut_after, &inside_after);
  EXPECT_NEAR(inside_after, inside, 1e-9 * (inside + cut));  // rigid: the inside is unchanged
  EXPECT_NEAR(cut_after, c.cost_after, 1e-9 * (inside + cut));
  // Still a manifold point, and the unused rows (a rank-d start) are still exactly zero.
  EXPECT_LT(LiftedManifold(r, g.d, g.num_poses).distance_from_manifold(Xc), 1e-12);
  EXPECT_TRUE((Xc.bottomRows(r - g.d).array() == 0.0).all());
  for (const auto& Z : c.motions) {
    const Eigen::MatrixXd G = Z.leftCols(r);
    EXPECT_LT((G.transpose() * G - Eigen::MatrixXd::Identity(r, r)).norm(), 1e-12);
  }
}

TEST(CoarseCorrection, UndoesARigidDriftOfTheBlocks) {
  // Noise-free measurements: the truth has f = 0, and blocks moved rigidly away from it are
  // exactly a coarse error; the correction brings them back.
  test::RandomGraphSpec spec;
  spec.poses = 90;
  spec.loop_closures = 60;
  spec.rotation_noise = 0;
  spec.translation_noise = 0;
  spec.seed = 8;
  const PoseGraph g = test::random_pose_graph(spec);
  const int r = 5;
  const std::vector<int> part = sequential_partition(g.num_poses, 6);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, part);
  const Eigen::MatrixXd X = drift_blocks(lift_poses(g.initial, r), g.d, part, 6, 0.3, 5);
  CoarseOptions o;
  o.max_iterations = 30;
  o.rel_tol = 0;
  const CoarseResult c = solve_all(layout, r, all_terms(g, layout, X), o);
  EXPECT_GT(c.cost_before, 1.0);
  EXPECT_LT(c.cost_after, 1e-8 * c.cost_before);
}

TEST(CoarseCorrection, WrongSizedTermsAreRejected) {
  const PoseGraph g = test::random_pose_graph(test::RandomGraphSpec());
  const std::vector<int> part = sequential_partition(g.num_poses, 3);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, part);
  auto terms = all_terms(g, layout, lift_poses(g.initial, 5));
  terms[1].pop_back();
  EXPECT_THROW(solve_all(layout, 5, terms, CoarseOptions()), std::runtime_error);
}

PoseGraph grid(std::size_t poses) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = poses;
  o.num_robots = 4;
  o.seed = 1;
  return generate_pose_graph(o).graph;
}

TEST(CoarseCorrection, TwoLevelRoundsAreDeterministicAndReachTheOptimumInFewerRounds) {
  const PoseGraph g = grid(800);
  const std::vector<int> part = sequential_partition(g.num_poses, 16);
  DistributedOptions opt;
  opt.grad_norm_tol = 0.01;
  const DistributedResult one = solve_distributed(g, part, opt);
  opt.coarse.enabled = true;
  const DistributedResult two = solve_distributed(g, part, opt);
  opt.delivery = DeliveryOrder::kShuffled;
  opt.delivery_seed = 5;
  const DistributedResult shuffled = solve_distributed(g, part, opt);
  EXPECT_EQ(two.stop_reason, "grad_norm");
  EXPECT_TRUE(two.X == shuffled.X);  // bit-identical: every agent solved the same coarse problem
  EXPECT_EQ(two.rounds, shuffled.rounds);
  EXPECT_NEAR(two.cost, one.cost, 1e-5 * one.cost);
  EXPECT_LT(two.rounds, one.rounds) << "one-level " << one.rounds << ", two-level " << two.rounds;
  // The coarse terms make the status messages larger, and only those.
  EXPECT_GT(two.bytes_exchanged / static_cast<std::uint64_t>(two.rounds),
            one.bytes_exchanged / static_cast<std::uint64_t>(one.rounds));
}

}  // namespace
}  // namespace tessera
