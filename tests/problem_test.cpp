// The lifted problem: data matrix, block objective, derivatives, manifold operations.

#include <random>

#include <gtest/gtest.h>

#include "manifold/lifted_manifold.hpp"
#include "problem/block_problem.hpp"
#include "problem/lifting.hpp"
#include "problem/objective.hpp"
#include "problem/rounding.hpp"
#include "random_graph.hpp"

namespace tessera {
namespace {

Eigen::MatrixXd random_point(const LiftedManifold& M, std::uint64_t seed) {
  std::srand(static_cast<unsigned>(seed));
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(M.rank(), M.cols());
  return M.project(X);
}

class ProblemTest : public ::testing::TestWithParam<int> {};

TEST_P(ProblemTest, TraceFormEqualsReferenceObjective) {
  const int d = GetParam();
  auto g = test::random_pose_graph({d, 25, 15, 0.05, 0.1, 3});
  // Perturb the poses so every residual is non-zero.
  std::vector<Pose> poses = g.initial;
  for (auto& p : poses) {
    p.t += Eigen::VectorXd::Random(d);
    p.R = project_to_rotation(p.R + 0.2 * Eigen::MatrixXd::Random(d, d));
  }
  auto P = BlockProblem::whole_graph(d, g.num_poses, g.measurements);
  const double f_ref = evaluate_objective(g, poses);
  for (int r : {d, d + 2}) {
    Eigen::MatrixXd X = lift_poses(poses, r);
    EXPECT_NEAR(P.cost(X), f_ref, 1e-9 * f_ref);
    EXPECT_NEAR(P.cost_share(X), f_ref, 1e-9 * f_ref);
  }
}

TEST_P(ProblemTest, EuclideanGradientMatchesFiniteDifferences) {
  const int d = GetParam();
  auto g = test::random_pose_graph({d, 12, 8, 0.05, 0.1, 4});
  auto P = BlockProblem::whole_graph(d, g.num_poses, g.measurements);
  Eigen::MatrixXd X = random_point(P.manifold(d + 1), 7);
  Eigen::MatrixXd G = P.euclidean_gradient(X);
  Eigen::MatrixXd D = Eigen::MatrixXd::Random(X.rows(), X.cols());
  const double h = 1e-6;
  double fd = (P.cost(X + h * D) - P.cost(X - h * D)) / (2 * h);
  EXPECT_NEAR(fd, G.cwiseProduct(D).sum(), 1e-5 * std::max(1.0, std::abs(fd)));
}

TEST_P(ProblemTest, RiemannianHessianMatchesFiniteDifferenceOfGradient) {
  const int d = GetParam();
  auto g = test::random_pose_graph({d, 12, 8, 0.05, 0.1, 5});
  auto P = BlockProblem::whole_graph(d, g.num_poses, g.measurements);
  const LiftedManifold M = P.manifold(d + 2);
  Eigen::MatrixXd X = random_point(M, 11);
  Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(X.rows(), X.cols()));
  Eigen::MatrixXd egrad = P.euclidean_gradient(X);
  Eigen::MatrixXd H = P.hessian_vector(X, egrad, V);
  // Along the retraction curve c(t) = R_X(tV): d/dt <grad f(c(t)), V> at 0 = <Hess f[V], V>
  // for a second-order retraction (the polar retraction is one).
  const double h = 1e-5;
  auto directional = [&](double t) {
    Eigen::MatrixXd Xt = M.retract(X, t * V);
    return P.cost(Xt);
  };
  double second = (directional(h) - 2 * directional(0) + directional(-h)) / (h * h);
  EXPECT_NEAR(second, H.cwiseProduct(V).sum(), 1e-3 * std::max(1.0, std::abs(second)));
  // Symmetry of the Hessian: <H[V], W> = <V, H[W]>.
  Eigen::MatrixXd W = M.tangent_project(X, Eigen::MatrixXd::Random(X.rows(), X.cols()));
  Eigen::MatrixXd HW = P.hessian_vector(X, egrad, W);
  EXPECT_NEAR(H.cwiseProduct(W).sum(), V.cwiseProduct(HW).sum(), 1e-8 * H.norm() * W.norm());
}

TEST_P(ProblemTest, ProjectionAndRetractionLandOnManifold) {
  const int d = GetParam();
  LiftedManifold M(d + 2, d, 40);
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(M.rank(), M.cols());
  Eigen::MatrixXd X = M.project(A);
  EXPECT_LT(M.distance_from_manifold(X), 1e-12);
  Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(M.rank(), M.cols()));
  EXPECT_LT(M.distance_from_manifold(M.retract(X, 3.0 * V)), 1e-12);
  // Tangency: Y_i^T V_i is skew for every pose.
  for (std::size_t i = 0; i < 40; ++i) {
    Eigen::MatrixXd S = X.middleCols((d + 1) * i, d).transpose() * V.middleCols((d + 1) * i, d);
    EXPECT_LT((S + S.transpose()).norm(), 1e-12);
  }
  // Projection is idempotent and the nearest point: translations untouched.
  EXPECT_LT((M.project(X) - X).norm(), 1e-12);
  for (std::size_t i = 0; i < 40; ++i)
    EXPECT_EQ(X.col((d + 1) * i + d), A.col((d + 1) * i + d));
}

TEST_P(ProblemTest, BlockCostSharesSumToGlobalCost) {
  const int d = GetParam();
  auto g = test::random_pose_graph({d, 40, 30, 0.05, 0.1, 6});
  auto whole = BlockProblem::whole_graph(d, g.num_poses, g.measurements);
  const int r = d + 1;
  Eigen::MatrixXd X = random_point(whole.manifold(r), 13);
  // Three blocks: ids mod 3 (many cut edges).
  double sum = 0.0;
  for (std::size_t b = 0; b < 3; ++b) {
    std::vector<std::size_t> owned;
    for (std::size_t i = b; i < g.num_poses; i += 3) owned.push_back(i);
    BlockProblem P(d, owned, g.measurements);
    auto gather = [&](const std::vector<std::size_t>& ids) {
      Eigen::MatrixXd Xb(r, (d + 1) * static_cast<Eigen::Index>(ids.size()));
      for (std::size_t k = 0; k < ids.size(); ++k)
        Xb.middleCols((d + 1) * k, d + 1) = X.middleCols((d + 1) * ids[k], d + 1);
      return Xb;
    };
    P.set_neighbor_poses(gather(P.neighbors()));
    Eigen::MatrixXd Xb = gather(owned);
    sum += P.cost_share(Xb);
    // The block gradient equals the global gradient restricted to the block.
    Eigen::MatrixXd G = whole.euclidean_gradient(X);
    Eigen::MatrixXd Gb = P.euclidean_gradient(Xb);
    for (std::size_t k = 0; k < owned.size(); ++k)
      EXPECT_LT((Gb.middleCols((d + 1) * k, d + 1) - G.middleCols((d + 1) * owned[k], d + 1)).norm(),
                1e-9 * (1.0 + G.norm()));
    // Block cost with neighbours fixed changes exactly like the global cost when only the
    // block moves.
    Eigen::MatrixXd D = Eigen::MatrixXd::Random(Xb.rows(), Xb.cols()) * 0.1;
    Eigen::MatrixXd X2 = X;
    for (std::size_t k = 0; k < owned.size(); ++k)
      X2.middleCols((d + 1) * owned[k], d + 1) += D.middleCols((d + 1) * k, d + 1);
    EXPECT_NEAR(P.cost(Xb + D) - P.cost(Xb), whole.cost(X2) - whole.cost(X),
                1e-9 * (1.0 + whole.cost(X)));
  }
  EXPECT_NEAR(sum, whole.cost(X), 1e-9 * whole.cost(X));
}

TEST_P(ProblemTest, RoundingRecoversPosesFromARotatedLift) {
  const int d = GetParam();
  std::vector<Pose> truth;
  auto g = test::random_pose_graph({d, 20, 10, 0.0, 0.0, 8}, &truth);
  const int r = d + 3;
  Eigen::MatrixXd X = lift_poses(truth, r);
  // Any orthogonal transform of the lift is the same solution.
  Eigen::MatrixXd O = project_to_rotation(Eigen::MatrixXd::Random(r, r));
  auto poses = round_solution(g, O * X);
  EXPECT_LT(evaluate_objective(g, poses), 1e-16 * g.num_measurements() + 1e-18);
}

INSTANTIATE_TEST_SUITE_P(Dimensions, ProblemTest, ::testing::Values(2, 3));

}  // namespace
}  // namespace tessera
