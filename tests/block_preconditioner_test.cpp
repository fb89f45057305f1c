// The block preconditioner: the exact Cholesky factor of Q_BB + lambda I, and the
// block-diagonal fallback used when that factor would be too large.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/block_preconditioner.hpp>
#include <utility>

#include "lifted_blocks.hpp"
#include "random_graph.hpp"

namespace tessera {
namespace {

struct Block {
  PoseGraph graph;
  std::vector<std::size_t> owned;
  std::vector<Measurement> measurements;
};

// The first half of a random graph's poses as a block; its neighbours are the others.
Block half_block(std::uint64_t seed) {
  test::HalfBlock h = test::half_block(3, seed);
  Block b;
  b.graph = std::move(h.graph);
  b.owned = std::move(h.owned);
  const std::size_t half = b.owned.size();  // the block is poses 0 .. half-1
  for (const auto& m : b.graph.measurements)
    if (m.i < half || m.j < half) b.measurements.push_back(m);
  return b;
}

TEST(BlockPreconditioner, ExactFactorInvertsTheShiftedDataMatrix) {
  const Block b = half_block(3);
  const BlockProblem problem(b.graph.d, b.owned, b.measurements);
  const double shift = 1e-6;
  const BlockPreconditioner precon(problem, shift, 0);
  EXPECT_FALSE(precon.block_diagonal());

  const int r = 5;
  const Eigen::MatrixXd X = lift_poses(b.graph.initial, r).leftCols(problem.data_matrix().rows());
  const LiftedManifold M = problem.manifold(r);
  const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(r, X.cols()));
  Eigen::MatrixXd A = Eigen::MatrixXd(problem.data_matrix());
  A.diagonal().array() += shift * A.diagonal().maxCoeff();
  const Eigen::MatrixXd expected = M.tangent_project(X, 0.5 * (V * A.inverse()));
  EXPECT_LT((precon.apply(M, X, V) - expected).norm(), 1e-8 * expected.norm());
}

// The exact factor against a dense solve of a well-conditioned shifted matrix, to round-off, for
// every rank the solvers use (and beyond), simplicial LDL^T and supernodal LL^T alike (chosen by
// the factor's entries or by its factorization's flops), and a supernodal factor converted to
// simplicial LDL^T for the solves.
TEST(BlockPreconditioner, ExactFactorMatchesADenseSolveForEveryRank) {
  for (int d : {2, 3})
    for (int mode : {0, 1, 2, 3}) {  // simplicial, supernodal by entries / flops, converted
      const std::size_t supernodal_from = mode == 1 ? 1 : 0;
      const double supernodal_flops = mode >= 2 ? 1.0 : 0.0;
      test::RandomGraphSpec spec;
      spec.d = d;
      spec.poses = 40;
      spec.loop_closures = 30;
      spec.seed = 11;
      Block b;
      b.graph = test::random_pose_graph(spec);
      for (std::size_t i = 0; i < spec.poses / 2; ++i) b.owned.push_back(i);
      const BlockProblem problem(d, b.owned, b.graph.measurements);
      const double shift = 1e-2;
      const BlockPreconditioner precon(problem, shift, 0, supernodal_from, supernodal_flops,
                                       mode == 3);
      EXPECT_FALSE(precon.block_diagonal());
      EXPECT_EQ(precon.supernodal(), mode != 0);
      Eigen::MatrixXd A = Eigen::MatrixXd(problem.data_matrix());
      A.diagonal().array() += shift * A.diagonal().maxCoeff();
      const Eigen::LLT<Eigen::MatrixXd> dense(A);
      for (int r = d; r <= 7; ++r) {
        const Eigen::MatrixXd X =
            lift_poses(b.graph.initial, r).leftCols(problem.data_matrix().rows());
        const LiftedManifold M = problem.manifold(r);
        const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(r, X.cols()));
        const Eigen::MatrixXd expected =
            M.tangent_project(X, 0.5 * dense.solve(V.transpose()).transpose());
        EXPECT_LT((precon.apply(M, X, V) - expected).cwiseAbs().maxCoeff(),
                  1e-12 * expected.cwiseAbs().maxCoeff())
            << "d = " << d << ", r = " << r << ", supernodal " << precon.supernodal();
      }
    }
}

// tCG needs a symmetric positive definite preconditioner on the tangent space.
TEST(BlockPreconditioner, IsSymmetricPositiveDefiniteOnTheTangentSpace) {
  const Block b = half_block(13);
  const BlockProblem problem(b.graph.d, b.owned, b.measurements);
  for (std::size_t max_entries : {std::size_t{0}, std::size_t{10}}) {  // exact, block diagonal
    const BlockPreconditioner precon(problem, 1e-6, max_entries);
    const int r = 5;
    const LiftedManifold M = problem.manifold(r);
    const Eigen::MatrixXd X = M.project(Eigen::MatrixXd::Random(r, problem.data_matrix().rows()));
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::MatrixXd u = M.tangent_project(X, Eigen::MatrixXd::Random(r, X.cols()));
      const Eigen::MatrixXd v = M.tangent_project(X, Eigen::MatrixXd::Random(r, X.cols()));
      const Eigen::MatrixXd Pu = precon.apply(M, X, u), Pv = precon.apply(M, X, v);
      const double uPv = u.cwiseProduct(Pv).sum(), vPu = v.cwiseProduct(Pu).sum();
      EXPECT_NEAR(uPv, vPu, 1e-10 * (std::abs(uPv) + std::abs(vPu)));
      EXPECT_GT(u.cwiseProduct(Pu).sum(), 0.0);
      EXPECT_GT(v.cwiseProduct(Pv).sum(), 0.0);
    }
  }
}

TEST(BlockPreconditioner, FallsBackToTheBlockDiagonalWhenTheFactorWouldBeTooLarge) {
  const Block b = half_block(5);
  const BlockProblem problem(b.graph.d, b.owned, b.measurements);
  const double shift = 1e-6;
  const BlockPreconditioner precon(problem, shift, /*max_factor_entries=*/10);
  ASSERT_TRUE(precon.block_diagonal());

  const int r = 4, w = b.graph.d + 1;
  const Eigen::MatrixXd X = lift_poses(b.graph.initial, r).leftCols(problem.data_matrix().rows());
  const LiftedManifold M = problem.manifold(r);
  const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(r, X.cols()));
  // Expected: V times the inverse of the block diagonal of Q_BB + lambda I.
  Eigen::MatrixXd A = Eigen::MatrixXd(problem.data_matrix());
  A.diagonal().array() += shift * A.diagonal().maxCoeff();
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(A.rows(), A.cols());
  for (Eigen::Index k = 0; k < A.rows(); k += w) D.block(k, k, w, w) = A.block(k, k, w, w);
  const Eigen::MatrixXd expected = M.tangent_project(X, 0.5 * (V * D.inverse()));
  EXPECT_LT((precon.apply(M, X, V) - expected).norm(), 1e-8 * expected.norm());
}

// falls_back() decides as the constructor does, from the symbolic analysis alone: for caps
// around the factor's predicted entries (below the lower triangle, between it and the fill, at
// and above the fill, none), the same answer as block_diagonal() of the constructed one.
TEST(BlockPreconditioner, FallsBackPredictsTheConstructorsChoiceWithoutFactoring) {
  const Block b = half_block(5);
  const BlockProblem problem(b.graph.d, b.owned, b.measurements);
  const double shift = 1e-6;
  const std::size_t entries = BlockPreconditioner(problem, shift, 0).factor_entries();
  ASSERT_GT(entries, 0u);
  const std::size_t n = static_cast<std::size_t>(problem.data_matrix().rows());
  bool saw_both[2] = {false, false};
  for (std::size_t cap :
       {std::size_t{10}, n, entries - 1, entries, entries + 1, 10 * entries, std::size_t{0}}) {
    const bool predicted = BlockPreconditioner::falls_back(problem, shift, cap);
    EXPECT_EQ(predicted, BlockPreconditioner(problem, shift, cap).block_diagonal()) << cap;
    saw_both[predicted] = true;
  }
  EXPECT_TRUE(saw_both[0] && saw_both[1]);                           // the caps cover both answers
  EXPECT_FALSE(BlockPreconditioner::falls_back(problem, shift, 0));  // 0 = no cap
}

TEST(BlockPreconditioner, BlockUpdateWithTheFallbackStillDecreasesTheLocalCost) {
  const Block b = half_block(7);
  BlockProblem problem(b.graph.d, b.owned, b.measurements);
  const int r = 5;
  // Perturbed start: lifted ground truth moved away along a random tangent direction.
  const Eigen::MatrixXd all = lift_poses(b.graph.initial, r);
  const Eigen::Index cols = problem.data_matrix().rows();
  problem.set_neighbor_poses(gather_pose_columns(all, problem.neighbors(), b.graph.d));
  const LiftedManifold M = problem.manifold(r);
  Eigen::MatrixXd X0 = all.leftCols(cols);
  X0 = M.retract(X0, 0.3 * M.tangent_project(X0, Eigen::MatrixXd::Random(r, cols)));

  BlockPreconditioner fallback(problem, 1e-6, 10);
  ASSERT_TRUE(fallback.block_diagonal());
  BlockUpdateOptions options;
  const Eigen::MatrixXd X1 = block_update(problem, X0, options, &fallback);
  EXPECT_LT(problem.cost(X1), 0.9 * problem.cost(X0));
}

// A cap at or above the dense lower triangle, n (n + 1) / 2 entries, is never exceeded whatever
// the ordering: falls_back() answers without an analysis, and as the constructor does.
TEST(BlockPreconditioner, FallsBackAgreesWithTheConstructorAroundTheDenseTriangleCap) {
  const Block b = half_block(5);
  const BlockProblem problem(b.graph.d, b.owned, b.measurements);
  const double shift = 1e-6;
  const std::size_t n = static_cast<std::size_t>(problem.data_matrix().rows());
  const std::size_t dense = n * (n + 1) / 2;
  for (std::size_t cap : {dense - 1, dense, dense + 1}) {
    EXPECT_FALSE(BlockPreconditioner::falls_back(problem, shift, cap)) << cap;
    EXPECT_FALSE(BlockPreconditioner(problem, shift, cap).block_diagonal()) << cap;
  }
}

}  // namespace
}  // namespace tessera
