// The tangent-coordinate block preconditioner J A^-1 J^T (solvers/tangent_preconditioner.hpp):
// exact inverse of the tangent-restricted Euclidean Hessian at the point it was factored at,
// tangent output, symmetric positive definite also when stale, the fallback to the Q_BB factor
// at rank r > d, and block solves reaching the same minimiser as with the Q_BB factor.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/QR>
#include <cstdlib>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/momentum.hpp>
#include <tessera/distributed/rbcd.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/block_preconditioner.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>

#include "lifted_blocks.hpp"
#include "random_graph.hpp"
#include "test_support.hpp"
#include "util/frobenius_inner.hpp"

namespace tessera {
namespace {

struct Block {
  PoseGraph graph;
  std::vector<std::size_t> owned;
  Eigen::MatrixXd all;  // lifted ground truth of every pose at the test's rank
};

Block half_block(int d, std::uint64_t seed, int r) {
  test::HalfBlock h = test::half_block(d, seed);
  Block b;
  b.graph = std::move(h.graph);
  b.owned = std::move(h.owned);
  b.all = lift_poses(b.graph.initial, r);
  return b;
}

Eigen::MatrixXd gather(const Eigen::MatrixXd& from, const std::vector<std::size_t>& which, int d) {
  return gather_pose_columns(from, which, d);
}

// 2 V Q as a matrix acting on the column-major vec of a d-row V: 2 (Q kron I_d).
Eigen::MatrixXd euclidean_hessian(const SparseMatrix& Q, int d) {
  const Eigen::MatrixXd Qd(Q);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(Qd.rows() * d, Qd.cols() * d);
  for (Eigen::Index a = 0; a < Qd.rows(); ++a)
    for (Eigen::Index b = 0; b < Qd.cols(); ++b)
      H.block(a * d, b * d, d, d) = 2.0 * Qd(a, b) * Eigen::MatrixXd::Identity(d, d);
  return H;
}

// At the point where A was factored (no shift), P V solves Proj_X(2 Z Q_BB) = V on the tangent
// space: P is the inverse of the tangent-restricted Euclidean Hessian. Checked against the
// defining equation and against a dense J A^-1 J^T, in 2D and 3D.
TEST(TangentPreconditioner, InvertsTheTangentRestrictedHessianAtItsPoint) {
  for (int d : {2, 3}) {
    const Block b = half_block(d, 5, d);
    const BlockProblem problem(d, b.owned, b.graph.measurements);
    TangentPreconditioner precon(problem, /*relative_shift=*/0.0, 0);
    ASSERT_TRUE(precon.usable());
    EXPECT_EQ(precon.coordinates_per_pose(), d * (d + 1) / 2);
    const LiftedManifold M = problem.manifold(d);
    std::srand(7);
    Eigen::MatrixXd X = gather(b.all, b.owned, d);
    X = M.retract(X, 0.3 * M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols())));
    ASSERT_TRUE(precon.factorize(X));
    EXPECT_TRUE(precon.factored());
    const SparseMatrix& Q = problem.data_matrix();
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols()));
      const Eigen::MatrixXd Z = precon.apply(M, X, V);
      // Tangent output.
      EXPECT_LT((M.tangent_project(X, Z) - Z).cwiseAbs().maxCoeff(),
                1e-12 * Z.cwiseAbs().maxCoeff());
      // Proj_X(2 Z Q) = V.
      const Eigen::MatrixXd HZ = M.tangent_project(X, 2.0 * (Z * Q));
      EXPECT_LT((HZ - V).cwiseAbs().maxCoeff(), 1e-8 * V.cwiseAbs().maxCoeff()) << "d = " << d;
      // Dense J A^-1 J^T.
      const Eigen::MatrixXd J = precon.basis(X);
      const Eigen::MatrixXd A = J.transpose() * euclidean_hessian(Q, d) * J;
      const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(V.data(), V.size());
      const Eigen::VectorXd z = J * A.ldlt().solve(J.transpose() * v);
      const Eigen::Map<const Eigen::VectorXd> got(Z.data(), Z.size());
      EXPECT_LT((got - z).cwiseAbs().maxCoeff(), 1e-8 * z.cwiseAbs().maxCoeff()) << "d = " << d;
    }
  }
}

// With the first-order multipliers Lambda(X) (factorize(X, egrad)), A is the Riemannian Hessian
// in tangent coordinates: near a minimiser (positive definite there) P inverts Proj_X(Hess f[.]),
// in 2D and 3D; and the supernodal factorization gives the same operator as the simplicial one.
TEST(TangentPreconditioner, WithMultipliersInvertsTheRiemannianHessianNearAMinimiser) {
  for (int d : {2, 3}) {
    const Block b = half_block(d, 5, d);
    BlockProblem problem(d, b.owned, b.graph.measurements);
    problem.set_neighbor_poses(gather(b.all, problem.neighbors(), d));
    TangentPreconditioner precon(problem, /*relative_shift=*/0.0, 0);
    TangentPreconditioner supernodal(problem, 0.0, 0, /*supernodal_min_flops=*/1.0);
    EXPECT_FALSE(precon.supernodal());
    EXPECT_TRUE(supernodal.supernodal());
    EXPECT_GT(precon.factor_flops(), 0.0);
    const LiftedManifold M = problem.manifold(d);
    std::srand(3);
    Eigen::MatrixXd X = gather(b.all, b.owned, d);
    X = M.retract(X, 0.01 * M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols())));
    const Eigen::MatrixXd egrad = problem.euclidean_gradient(X);
    ASSERT_TRUE(precon.factorize(X, egrad));
    ASSERT_TRUE(supernodal.factorize(X, egrad));
    EXPECT_TRUE(precon.with_multipliers());
    EXPECT_TRUE(supernodal.with_multipliers());
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols()));
      const Eigen::MatrixXd HV = M.tangent_project(X, problem.hessian_vector(X, egrad, V));
      const Eigen::MatrixXd Z = precon.apply(M, X, HV);
      EXPECT_LT((Z - V).cwiseAbs().maxCoeff(), 1e-8 * V.cwiseAbs().maxCoeff()) << "d = " << d;
      const Eigen::MatrixXd Zs = supernodal.apply(M, X, HV);
      EXPECT_LT((Zs - Z).cwiseAbs().maxCoeff(), 1e-8 * Z.cwiseAbs().maxCoeff()) << "d = " << d;
    }
    // Without the multipliers the factor is the Euclidean restriction again.
    ASSERT_TRUE(precon.factorize(X));
    EXPECT_FALSE(precon.with_multipliers());
  }
}

// A factor from an earlier point (refresh interval 0) stays a symmetric positive definite map
// of the current tangent space to itself: tCG's requirement.
TEST(TangentPreconditioner, StaleFactorIsSymmetricPositiveDefiniteOnTheCurrentTangentSpace) {
  for (int d : {2, 3}) {
    const Block b = half_block(d, 9, d);
    const BlockProblem problem(d, b.owned, b.graph.measurements);
    TangentPreconditioner precon(problem);
    const LiftedManifold M = problem.manifold(d);
    std::srand(3);
    const Eigen::MatrixXd X0 = gather(b.all, b.owned, d);
    ASSERT_TRUE(precon.factorize(X0));
    const Eigen::MatrixXd X =
        M.retract(X0, 0.5 * M.tangent_project(X0, Eigen::MatrixXd::Random(d, X0.cols())));
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::MatrixXd u = M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols()));
      const Eigen::MatrixXd v = M.tangent_project(X, Eigen::MatrixXd::Random(d, X.cols()));
      const Eigen::MatrixXd Pu = precon.apply(M, X, u), Pv = precon.apply(M, X, v);
      EXPECT_LT((M.tangent_project(X, Pu) - Pu).cwiseAbs().maxCoeff(),
                1e-12 * Pu.cwiseAbs().maxCoeff());
      const double uPv = frobenius_inner(u, Pv), vPu = frobenius_inner(v, Pu);
      EXPECT_NEAR(uPv, vPu, 1e-10 * (std::abs(uPv) + std::abs(vPu)));
      EXPECT_GT(frobenius_inner(u, Pu), 0.0);
    }
  }
}

// prepare(): factored at the first call, then again every `refresh_interval` calls (0: never).
TEST(TangentPreconditioner, PrepareRefactorsEveryRefreshInterval) {
  const Block b = half_block(3, 2, 3);
  const BlockProblem problem(3, b.owned, b.graph.measurements);
  const Eigen::MatrixXd X = gather(b.all, b.owned, 3);
  TangentPreconditioner once(problem), every2(problem);
  for (int k = 0; k < 5; ++k) {
    EXPECT_TRUE(once.prepare(X, 0));
    EXPECT_TRUE(every2.prepare(X, 2));
  }
  EXPECT_EQ(once.factorizations(), 1);
  EXPECT_EQ(every2.factorizations(), 3);  // calls 1, 3, 5
}

// Rank r > d (a point with no zero rows, e.g. after a saddle escape or a rotated lifting): the
// tangent factor refuses it, and an agent's update falls back to the Q_BB factor; at the active
// rows of a lifted start (rank d) the agent uses the tangent factor. A factor predicted too large
// is not usable either.
TEST(TangentPreconditioner, FallsBackToTheDataMatrixFactorAboveRankD) {
  const int d = 3, r = 5;
  const Block b = half_block(d, 4, r);
  const BlockProblem problem(d, b.owned, b.graph.measurements);
  TangentPreconditioner precon(problem);
  const Eigen::MatrixXd Y0 = gather(b.all, b.owned, d);
  EXPECT_FALSE(precon.factorize(Y0));  // 5 rows
  EXPECT_FALSE(precon.prepare(Y0, 0));
  EXPECT_FALSE(TangentPreconditioner(problem, 1e-9, /*max_factor_entries=*/10).usable());

  std::vector<int> a(b.graph.num_poses);
  for (std::size_t i = 0; i < b.graph.num_poses; ++i) a[i] = i < b.owned.size() ? 0 : 1;
  const BlockLayout layout = make_block_layout(b.graph.num_poses, b.graph.measurements, a);
  const Eigen::MatrixXd Yn = gather(b.all, problem.neighbors(), d);
  std::srand(5);
  const LiftedManifold M = problem.manifold(r);
  Eigen::MatrixXd start =
      M.retract(Y0, 0.2 * M.tangent_project(Y0, Eigen::MatrixXd::Random(r, Y0.cols())));
  start.bottomRows(r - d).setZero();
  start = M.project(start);
  const BlockUpdateOptions options;  // tangent by default
  AgentState lifted(0, d, layout, b.graph.measurements, start, options);
  const Eigen::MatrixXd moved = lifted.update(start, Yn, options);
  EXPECT_GT((moved - start).norm(), 1e-6);
  EXPECT_EQ(lifted.block_updates(), 1);
  EXPECT_EQ(lifted.tangent_updates(), 1);
  EXPECT_EQ(lifted.tangent_factorizations(), 1);

  const Eigen::MatrixXd R =
      Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd::Random(r, r)).householderQ();
  AgentState rotated(0, d, layout, b.graph.measurements, R * start, options);
  const Eigen::MatrixXd got = rotated.update(R * start, R * Yn, options);
  EXPECT_EQ(rotated.block_updates(), 1);
  EXPECT_EQ(rotated.tangent_updates(), 0);
  // The Q_BB-preconditioned update, computed directly.
  BlockProblem full(d, b.owned, b.graph.measurements);
  full.set_neighbor_poses(R * Yn);
  BlockPreconditioner euclidean(full);
  const Eigen::MatrixXd want = block_update(full, R * start, options, &euclidean);
  EXPECT_LT((got - want).cwiseAbs().maxCoeff(), 1e-10);
}

// Repeated block updates (neighbours fixed) with the tangent factor (built once at the start,
// or refreshed at every update) and with the Q_BB factor reach the same minimiser of the
// block's objective.
TEST(TangentPreconditioner, BlockSolveReachesTheSameMinimiserAsTheDataMatrixFactor) {
  for (int d : {2, 3})
    for (int refresh : {0, 1}) {
      const Block b = half_block(d, 12, d);
      BlockProblem problem(d, b.owned, b.graph.measurements);
      problem.set_neighbor_poses(gather(b.all, problem.neighbors(), d));
      const LiftedManifold M = problem.manifold(d);
      std::srand(11);
      Eigen::MatrixXd X0 = gather(b.all, b.owned, d);
      X0 = M.retract(X0, 0.3 * M.tangent_project(X0, Eigen::MatrixXd::Random(d, X0.cols())));
      BlockPreconditioner euclidean(problem);
      TangentPreconditioner tangent(problem);
      BlockUpdateOptions options;
      Eigen::MatrixXd Xe = X0, Xt = X0;
      long long tcg_e = 0, tcg_t = 0;
      for (int k = 0; k < 150; ++k) {
        BlockUpdateStats se, st;
        Xe = block_update(problem, Xe, options, &euclidean, nullptr, nullptr, &se);
        ASSERT_TRUE(tangent.prepare(Xt, refresh));
        Xt = block_update(problem, Xt, options, nullptr, nullptr, &tangent, &st);
        EXPECT_FALSE(se.tangent);
        EXPECT_TRUE(st.tangent);
        tcg_e += se.tcg_iterations;
        tcg_t += st.tcg_iterations;
      }
      const auto grad_norm = [&](const Eigen::MatrixXd& X) {
        return problem.riemannian_gradient(X, problem.euclidean_gradient(X)).norm();
      };
      // Both reach the round-off floor of the cost (information weights ~2500: a step's decrease
      // at ||grad|| ~1e-6 is below 1e-14 f), from a start far from it.
      ASSERT_GT(grad_norm(X0), 1.0);
      EXPECT_LT(grad_norm(Xe), 1e-5) << "d = " << d;
      EXPECT_LT(grad_norm(Xt), 1e-5) << "d = " << d << ", refresh " << refresh;
      EXPECT_NEAR(problem.cost(Xt), problem.cost(Xe), 1e-13 * std::abs(problem.cost(Xe)));
      EXPECT_LT((Xt - Xe).cwiseAbs().maxCoeff(), 1e-6) << "d = " << d << ", refresh " << refresh;
      EXPECT_EQ(tangent.factorizations(), refresh == 0 ? 1 : 150);
      EXPECT_GT(tcg_t, 0);
      EXPECT_GT(tcg_e, 0);
    }
}

// Far over the cap, the pose-level pattern's estimate alone rules the factor out (A is never
// built); near the cap the exact analysis decides as before. The estimate is close to the
// exact count, so it never rules out a factor the cap would have allowed.
TEST(TangentPreconditioner, APoseLevelEstimateRulesOutOnlyFactorsFarOverTheCap) {
  for (int d : {2, 3}) {
    const Block b = half_block(d, 6, d);
    const BlockProblem problem(d, b.owned, b.graph.measurements);
    const std::size_t exact = TangentPreconditioner(problem, 1e-9, 0).factor_entries();
    ASSERT_GT(exact, 100u);
    const TangentPreconditioner at_cap(problem, 1e-9, exact);
    EXPECT_TRUE(at_cap.usable()) << "d = " << d;
    EXPECT_EQ(at_cap.factor_entries(), exact);
    const TangentPreconditioner below(problem, 1e-9, exact - 1);
    EXPECT_FALSE(below.usable());
    EXPECT_EQ(below.factor_entries(), exact) << "decided by the exact analysis";
    const TangentPreconditioner far_below(problem, 1e-9, exact / 4);
    EXPECT_FALSE(far_below.usable());
    const double estimate = static_cast<double>(far_below.factor_entries());
    EXPECT_GT(estimate, 0.5 * static_cast<double>(exact)) << "d = " << d;
    EXPECT_LT(estimate, 2.0 * static_cast<double>(exact)) << "d = " << d;
  }
}

TEST(TangentPreconditioner, OptionsAreValidated) {
  BlockUpdateOptions o;
  o.tangent_refresh_interval = -1;
  EXPECT_TRUE(test::validation_names(o, "tangent_refresh_interval"));
  o = BlockUpdateOptions{};
  o.tangent_relative_shift = -1e-9;
  EXPECT_THROW(o.validate(), InputError);
  o.tangent_relative_shift = 1e-9;
  o.tangent_radius_scale = 0.0;
  EXPECT_TRUE(test::validation_names(o, "tangent_radius_scale"));
  o = BlockUpdateOptions{};
  o.tangent_relative_shift = std::nan("");
  EXPECT_TRUE(test::validation_names(o, "tangent_relative_shift"));
}

}  // namespace
}  // namespace tessera
