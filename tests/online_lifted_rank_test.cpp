// A staircase's higher-rank optimum brought back to the online run's rank: exact (every
// residual kept) for a point of rank d, whatever frame of the larger lifted space it sits in.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <random>
#include <stdexcept>
#include <tessera/generate/generator.hpp>
#include <tessera/online/lifted_rank.hpp>

namespace tessera {
namespace {

double lifted_cost(const PoseGraph& g, const Eigen::MatrixXd& X) {
  const int d = g.d;
  const Eigen::Index w = d + 1;
  double f = 0.0;
  for (const Measurement& m : g.measurements) {
    const auto Yi = X.middleCols(w * static_cast<Eigen::Index>(m.i), d);
    const auto Yj = X.middleCols(w * static_cast<Eigen::Index>(m.j), d);
    const auto pi = X.col(w * static_cast<Eigen::Index>(m.i) + d);
    const auto pj = X.col(w * static_cast<Eigen::Index>(m.j) + d);
    f += m.kappa * (Yj - Yi * m.R).squaredNorm() + m.tau * (pj - pi - Yi * m.t).squaredNorm();
  }
  return f;
}

TEST(ProjectToRank, ARankDOptimumInAHigherRankFrameComesBackWithEveryResidualKept) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kSphere;
  o.num_poses = 80;
  o.num_robots = 2;
  o.seed = 6;
  const GeneratorResult gen = generate_pose_graph(o);
  const int d = gen.graph.d, r = 5;
  const Eigen::Index w = d + 1;
  // The true poses, a rank-d point, at rank r + 1 in a random frame with an offset (where a
  // staircase climb from rank r may leave it).
  Eigen::MatrixXd X =
      Eigen::MatrixXd::Zero(r + 1, w * static_cast<Eigen::Index>(gen.graph.num_poses));
  for (std::size_t k = 0; k < gen.graph.num_poses; ++k) {
    X.block(0, w * static_cast<Eigen::Index>(k), d, d) = gen.ground_truth[k].R;
    X.block(0, w * static_cast<Eigen::Index>(k) + d, d, 1) = gen.ground_truth[k].t;
  }
  std::mt19937 rng(2);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd A(r + 1, r + 1);
  for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = normal(rng);
  const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(A).householderQ();
  X = (Q * X).eval();
  const Eigen::VectorXd offset = Eigen::VectorXd::LinSpaced(r + 1, -7.0, 9.0);
  for (std::size_t k = 0; k < gen.graph.num_poses; ++k)
    X.col(w * static_cast<Eigen::Index>(k) + d) += offset;
  const double before = lifted_cost(gen.graph, X);
  ASSERT_GT(before, 1.0);  // noisy measurements: a real cost to keep

  const Eigen::MatrixXd P = project_to_rank(X, d, r);
  ASSERT_EQ(P.rows(), r);
  ASSERT_EQ(P.cols(), X.cols());
  EXPECT_NEAR(lifted_cost(gen.graph, P), before, 1e-9 * before);
  for (std::size_t k = 0; k < gen.graph.num_poses; ++k) {
    const auto Yk = P.middleCols(w * static_cast<Eigen::Index>(k), d);
    EXPECT_LT((Yk.transpose() * Yk - Eigen::MatrixXd::Identity(d, d)).norm(), 1e-12);
  }
  EXPECT_TRUE(project_to_rank(X, d, r + 1) == X);
  EXPECT_THROW(project_to_rank(X, d, d - 1), std::invalid_argument);
  EXPECT_THROW(project_to_rank(X, d, r + 2), std::invalid_argument);
}

}  // namespace
}  // namespace tessera
