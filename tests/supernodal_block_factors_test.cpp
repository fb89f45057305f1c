// The agents' factors computed supernodally and solved in the simplicial form: the tangent
// preconditioner with simplicial_solves (solvers/tangent_preconditioner.hpp) and the distributed
// certificate's block factor (certification/shifted_block_factor.hpp). Both are the operators of
// their simplicial counterparts up to round-off, refactor, and report "not positive definite".

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdlib>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <tessera/util/input_error.hpp>
#include <vector>

#include "certification/shifted_block_factor.hpp"
#include "lifted_blocks.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

// Supernodal factorization with simplicial solves applies the same J A^-1 J^T as the simplicial
// factor, with and without the multipliers, and again after a refactorization at another point
// (the converted factor is re-analysed supernodally): 2D and 3D.
TEST(SupernodalBlockFactors, TangentFactorWithSimplicialSolvesIsTheSimplicialOperator) {
  for (int d : {2, 3}) {
    test::HalfBlock h = test::half_block(d, 5);
    BlockProblem problem(d, h.owned, h.graph.measurements);
    const Eigen::MatrixXd all = lift_poses(h.graph.initial, d);
    problem.set_neighbor_poses(gather_pose_columns(all, problem.neighbors(), d));
    TangentPreconditioner simplicial(problem, 1e-9, 0);
    TangentPreconditioner converted(problem, 1e-9, 0, /*supernodal_min_flops=*/1.0,
                                    /*simplicial_solves=*/true);
    EXPECT_FALSE(simplicial.supernodal_factorization());
    EXPECT_TRUE(converted.supernodal_factorization());
    EXPECT_FALSE(converted.supernodal()) << "its solves are simplicial";
    ASSERT_TRUE(converted.usable());
    const LiftedManifold M = problem.manifold(d);
    std::srand(11);
    Eigen::MatrixXd X = gather_pose_columns(all, h.owned, d);
    for (int point = 0; point < 3; ++point) {
      X = M.retract(X, 0.01 * M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols())));
      const Eigen::MatrixXd egrad = problem.euclidean_gradient(X);
      if (point == 1) {
        ASSERT_TRUE(simplicial.factorize(X, egrad));
        ASSERT_TRUE(converted.factorize(X, egrad));
        EXPECT_EQ(converted.with_multipliers(), simplicial.with_multipliers());
      } else {
        ASSERT_TRUE(simplicial.factorize(X));
        ASSERT_TRUE(converted.factorize(X));
      }
      const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols()));
      const Eigen::MatrixXd Z = simplicial.apply(M, X, V);
      const Eigen::MatrixXd Zc = converted.apply(M, X, V);
      EXPECT_LT((Zc - Z).cwiseAbs().maxCoeff(), 1e-8 * Z.cwiseAbs().maxCoeff())
          << "d = " << d << ", point " << point;
    }
    EXPECT_EQ(converted.factorizations(), 3);
  }
}

// Below the flops threshold nothing changes: the factor stays simplicial.
TEST(SupernodalBlockFactors, TangentFactorBelowTheThresholdStaysSimplicial) {
  test::HalfBlock h = test::half_block(3, 6);
  const BlockProblem problem(3, h.owned, h.graph.measurements);
  const TangentPreconditioner below(problem, 1e-9, 0, 1e300, true);
  EXPECT_FALSE(below.supernodal_factorization());
  EXPECT_GT(below.factor_flops(), 0.0);
}

// Near the threshold (within the pose-level estimate's margin) the exact analysis decides, and
// a factor just above it is converted too: the same operator at its point.
TEST(SupernodalBlockFactors, NearTheThresholdTheExactAnalysisDecides) {
  for (int d : {2, 3}) {
    test::HalfBlock h = test::half_block(d, 8);
    BlockProblem problem(d, h.owned, h.graph.measurements);
    const Eigen::MatrixXd all = lift_poses(h.graph.initial, d);
    problem.set_neighbor_poses(gather_pose_columns(all, problem.neighbors(), d));
    TangentPreconditioner simplicial(problem, 1e-9, 0);
    const double flops = simplicial.factor_flops();
    ASSERT_GT(flops, 0.0);
    EXPECT_FALSE(
        TangentPreconditioner(problem, 1e-9, 0, 1.1 * flops, true).supernodal_factorization())
        << "d = " << d;
    TangentPreconditioner converted(problem, 1e-9, 0, 0.9 * flops, true);
    EXPECT_TRUE(converted.supernodal_factorization()) << "d = " << d;
    const LiftedManifold M = problem.manifold(d);
    std::srand(17);
    Eigen::MatrixXd X = gather_pose_columns(all, h.owned, d);
    X = M.retract(X, 0.01 * M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols())));
    ASSERT_TRUE(simplicial.factorize(X));
    ASSERT_TRUE(converted.factorize(X));
    const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols()));
    const Eigen::MatrixXd Z = simplicial.apply(M, X, V);
    EXPECT_LT((converted.apply(M, X, V) - Z).cwiseAbs().maxCoeff(), 1e-8 * Z.cwiseAbs().maxCoeff())
        << "d = " << d;
  }
}

TEST(SupernodalBlockFactors, TangentThresholdOptionIsValidated) {
  BlockUpdateOptions o;
  o.tangent_supernodal_min_flops = -1.0;
  EXPECT_TRUE(test::validation_names(o, "tangent_supernodal_min_flops"));
  o.tangent_supernodal_min_flops = std::nan("");
  EXPECT_THROW(o.validate(), InputError);
}

// The certificate's block factor solves (S + shift I) z = r like a dense Cholesky solve, says
// "not positive definite" for a shift below -lambda_min(S), and factors after a larger shift.
TEST(SupernodalBlockFactors, ShiftedBlockFactorSolvesAndRejectsIndefiniteShifts) {
  for (int d : {2, 3}) {
    test::HalfBlock h = test::half_block(d, 7);
    const BlockProblem problem(d, h.owned, h.graph.measurements);
    const SparseMatrix& S = problem.data_matrix();  // positive semidefinite, with a gauge
    const int w = d + 1;
    const Eigen::MatrixXd Sd(S);
    const double top = Sd.diagonal().maxCoeff();
    ShiftedBlockFactor factor(S, w);
    EXPECT_FALSE(factor.factor(S, -0.5 * top)) << "d = " << d;
    ASSERT_TRUE(factor.factor(S, 1e-6 * top)) << "d = " << d;
    std::srand(13);
    const Eigen::MatrixXd r = Eigen::MatrixXd::Random(1, S.cols());
    const Eigen::MatrixXd z = factor.solve(r);
    const Eigen::MatrixXd shifted = Sd + 1e-6 * top * Eigen::MatrixXd::Identity(S.rows(), S.cols());
    const Eigen::VectorXd expect = shifted.llt().solve(r.transpose());
    EXPECT_LT((z.transpose() - expect).cwiseAbs().maxCoeff(), 1e-8 * expect.cwiseAbs().maxCoeff())
        << "d = " << d;
  }
}

}  // namespace
}  // namespace tessera
