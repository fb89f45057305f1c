// Exact translation solves by substructuring (distributed/translation_interface_solve.hpp):
// each block's factor plus the team's interface Schur complement solve the whole graph's
// translation Laplacian, and every agent ends up with the same interface values.

#include "distributed/translation_interface_solve.hpp"

#include <gtest/gtest.h>

#include <random>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/block_problem.hpp>
#include <vector>

#include "refine_harness.hpp"

namespace tessera {
namespace {

// The translation Laplacian of the whole graph (pose order), from the centralized Q.
SparseMatrix translation_laplacian(const PoseGraph& g) {
  std::vector<std::size_t> all(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) all[i] = i;
  const BlockProblem whole(g.d, all, g.measurements);
  const SparseMatrix& Q = whole.data_matrix();
  const Eigen::Index w = g.d + 1;
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index c = w - 1; c < Q.outerSize(); c += w)
    for (SparseMatrix::InnerIterator it(Q, c); it; ++it)
      if (it.row() % w == w - 1) t.emplace_back(it.row() / w, c / w, it.value());
  SparseMatrix L(static_cast<Eigen::Index>(g.num_poses), static_cast<Eigen::Index>(g.num_poses));
  L.setFromTriplets(t.begin(), t.end());
  return L;
}

TEST(TranslationInterfaceSolve, SolvesTheWholeGraphsLaplacianFromTheBlocksAndOneInterfaceSum) {
  const PoseGraph g = test::refine_chain(400, 5);
  const int N = 4;
  const std::vector<int> parts = sequential_partition(g.num_poses, N);
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, parts);
  std::vector<BlockProblem> problems;
  std::vector<std::unique_ptr<TranslationInterfaceSolve>> solves;
  for (int b = 0; b < N; ++b) {
    problems.emplace_back(g.d, layout.poses[static_cast<std::size_t>(b)], g.measurements);
  }
  for (int b = 0; b < N; ++b)
    solves.push_back(std::make_unique<TranslationInterfaceSolve>(
        problems[static_cast<std::size_t>(b)], layout, b));
  const Eigen::Index team = solves[0]->team_size();
  EXPECT_EQ(team, interface_pose_count(layout));
  EXPECT_GT(team, 0);
  EXPECT_LT(team, 60);  // a chain in 4 pieces and a few closures: a handful of poses a block
  std::vector<std::vector<double>> shares;
  for (const auto& s : solves) shares.push_back(s->share());
  std::vector<const std::vector<double>*> ptrs;
  for (const auto& v : shares) ptrs.push_back(&v);
  for (const auto& s : solves) ASSERT_TRUE(s->assemble(ptrs));

  // A right-hand side in L's range (columns summing to zero), k = 3 columns.
  const Eigen::Index n = static_cast<Eigen::Index>(g.num_poses), k = 3;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd rhs(n, k);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index c = 0; c < k; ++c) rhs(i, c) = normal(rng);
  rhs.rowwise() -= rhs.colwise().mean();

  // Each block's forward solve and interface residual; the team's rhat in id order.
  std::vector<Eigen::MatrixXd> y(static_cast<std::size_t>(N));
  Eigen::MatrixXd rhat(team, k);
  for (int b = 0; b < N; ++b) {
    const auto& poses = layout.poses[static_cast<std::size_t>(b)];
    Eigen::MatrixXd own(static_cast<Eigen::Index>(poses.size()), k);
    for (std::size_t i = 0; i < poses.size(); ++i)
      own.row(static_cast<Eigen::Index>(i)) = rhs.row(static_cast<Eigen::Index>(poses[i]));
    solves[static_cast<std::size_t>(b)]->forward(own, y[static_cast<std::size_t>(b)]);
    rhat.middleRows(solves[0]->block_offset(b), solves[0]->block_size(b)) =
        solves[static_cast<std::size_t>(b)]->interface_residual(y[static_cast<std::size_t>(b)]);
  }
  // Every agent solves the same Sigma to the same bits.
  const Eigen::MatrixXd u = solves[0]->solve_interface(rhat);
  for (int b = 1; b < N; ++b)
    EXPECT_EQ(solves[static_cast<std::size_t>(b)]->solve_interface(rhat), u);
  Eigen::MatrixXd x(n, k);
  for (int b = 0; b < N; ++b) {
    const auto& poses = layout.poses[static_cast<std::size_t>(b)];
    const Eigen::MatrixXd xb =
        solves[static_cast<std::size_t>(b)]->back(y[static_cast<std::size_t>(b)], u);
    for (std::size_t i = 0; i < poses.size(); ++i) {
      x.row(static_cast<Eigen::Index>(poses[i])) = xb.row(static_cast<Eigen::Index>(i));
      const Eigen::Index at = solves[0]->team_row(poses[i]);
      if (at >= 0) {  // an interface pose: its row is u's, bit for bit
        EXPECT_EQ(Eigen::MatrixXd(xb.row(static_cast<Eigen::Index>(i))),
                  Eigen::MatrixXd(u.row(at)));
      }
    }
  }
  const SparseMatrix L = translation_laplacian(g);
  const double residual = (L * x - rhs).norm() / rhs.norm();
  EXPECT_LT(residual, 1e-10);
}

// The distributed rounding lets one agent factor Sigma and send u: the others assemble without
// a factor, which checks the shares alike (a block whose L_BB is singular makes every agent
// fall back) and leaves them not ready; their back solves take that agent's u.
TEST(TranslationInterfaceSolve, AnAssembleWithoutAFactorChecksTheSharesAndIsNotReady) {
  const PoseGraph g = test::refine_chain(200, 3);
  const int N = 3;
  const BlockLayout layout =
      make_block_layout(g.num_poses, g.measurements, sequential_partition(g.num_poses, N));
  std::vector<BlockProblem> problems;
  for (int b = 0; b < N; ++b)
    problems.emplace_back(g.d, layout.poses[static_cast<std::size_t>(b)], g.measurements);
  std::vector<std::unique_ptr<TranslationInterfaceSolve>> solves;
  for (int b = 0; b < N; ++b)
    solves.push_back(std::make_unique<TranslationInterfaceSolve>(
        problems[static_cast<std::size_t>(b)], layout, b));
  std::vector<std::vector<double>> shares;
  for (const auto& s : solves) shares.push_back(s->share());
  std::vector<const std::vector<double>*> ptrs;
  for (const auto& v : shares) ptrs.push_back(&v);
  EXPECT_TRUE(solves[0]->assemble(ptrs));
  EXPECT_TRUE(solves[0]->ready());
  EXPECT_TRUE(solves[1]->assemble(ptrs, false));
  EXPECT_FALSE(solves[1]->ready());
  // A block that reports a singular L_BB: no agent goes on, factor or not.
  const std::vector<double> singular{0.0};
  ptrs[2] = &singular;
  EXPECT_FALSE(solves[1]->assemble(ptrs, false));
  EXPECT_FALSE(solves[0]->assemble(ptrs));
}

// L_BB holds the block's cut measurements on its diagonal, so a pose whose measurements are all
// cut ones still makes it positive definite; a pose without any measurement does not, and the
// block says so (the refinement then falls back to its block-Jacobi translation CG).
TEST(TranslationInterfaceSolve, ABlockWithAPoseWithoutMeasurementsReportsNoFactor) {
  // The chain 0-1-2-3-4-5; pose 6 has no measurement.
  PoseGraph g;
  g.d = 2;
  g.num_poses = 7;
  for (std::size_t i = 0; i + 1 < 6; ++i) {
    Measurement m;
    m.i = i;
    m.j = i + 1;
    m.R = Eigen::Matrix2d::Identity();
    m.t = Eigen::Vector2d(1.0, 0.0);
    g.measurements.push_back(m);
  }
  // Pose 4 in block 0 has only cut measurements (3-4, 4-5): positive definite.
  const std::vector<int> cut_only{0, 0, 1, 1, 0, 1, 1};
  const BlockLayout a = make_block_layout(g.num_poses, g.measurements, cut_only);
  const BlockProblem pa(g.d, a.poses[0], g.measurements);
  EXPECT_EQ(TranslationInterfaceSolve(pa, a, 0).share().front(), 1.0);
  // Pose 6 in block 0: L_BB has a zero row.
  const std::vector<int> lone{0, 0, 1, 1, 1, 1, 0};
  const BlockLayout b = make_block_layout(g.num_poses, g.measurements, lone);
  const BlockProblem pb(g.d, b.poses[0], g.measurements);
  EXPECT_EQ(TranslationInterfaceSolve(pb, b, 0).share(), std::vector<double>{0.0});
}

}  // namespace
}  // namespace tessera
