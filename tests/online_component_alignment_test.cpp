// Pieces of a growing graph that meet: the first measurement that links two pieces moves the
// smaller one rigidly so that it has zero residual, whatever rigid motion of the lifted space
// (reflections included) separated the pieces, and leaves each piece's own residuals as they were.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <random>
#include <tessera/generate/generator.hpp>
#include <tessera/online/component_alignment.hpp>

namespace tessera {
namespace {

constexpr int kRank = 5;

// Lifted cost of measurements [first, last) at X (r x (d+1)n).
double lifted_cost(const PoseGraph& g, const Eigen::MatrixXd& X, std::size_t first,
                   std::size_t last) {
  const int d = g.d;
  const Eigen::Index w = d + 1;
  double f = 0.0;
  for (std::size_t e = first; e < last; ++e) {
    const Measurement& m = g.measurements[e];
    const auto Yi = X.middleCols(w * static_cast<Eigen::Index>(m.i), d);
    const auto Yj = X.middleCols(w * static_cast<Eigen::Index>(m.j), d);
    const auto pi = X.col(w * static_cast<Eigen::Index>(m.i) + d);
    const auto pj = X.col(w * static_cast<Eigen::Index>(m.j) + d);
    f += m.kappa * (Yj - Yi * m.R).squaredNorm() + m.tau * (pj - pi - Yi * m.t).squaredNorm();
  }
  return f;
}

Eigen::MatrixXd random_orthogonal(int r, std::mt19937& rng, bool reflect) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::MatrixXd A(r, r);
  for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = n(rng);
  Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(A).householderQ();
  if ((Q.determinant() < 0) != reflect) Q.col(0) *= -1.0;
  return Q;
}

// Two robots' noise-free trajectories: the ground truth, lifted into the top d rows, has
// zero cost. Measurements are reordered: robot 0's own, robot 1's own, then those linking them.
struct TwoPieces {
  PoseGraph graph;
  Eigen::MatrixXd X;    // zero-cost lifted iterate
  std::size_t own = 0;  // measurements inside one robot (the first `own`)
};

TwoPieces two_noise_free_robots() {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = 120;
  o.num_robots = 2;
  o.seed = 4;
  o.rotation_noise = 0.0;
  o.translation_noise = 0.0;
  const GeneratorResult gen = generate_pose_graph(o);
  TwoPieces out;
  out.graph = gen.graph;
  out.graph.measurements.clear();
  std::vector<Measurement> links;
  for (const Measurement& m : gen.graph.measurements)
    if (gen.robot_of[m.i] == gen.robot_of[m.j])
      out.graph.measurements.push_back(m);
    else
      links.push_back(m);
  out.own = out.graph.measurements.size();
  out.graph.measurements.insert(out.graph.measurements.end(), links.begin(), links.end());
  const int d = out.graph.d;
  const Eigen::Index w = d + 1;
  out.X = Eigen::MatrixXd::Zero(kRank, w * static_cast<Eigen::Index>(out.graph.num_poses));
  for (std::size_t k = 0; k < out.graph.num_poses; ++k) {
    out.X.block(0, w * static_cast<Eigen::Index>(k), d, d) = gen.ground_truth[k].R;
    out.X.block(0, w * static_cast<Eigen::Index>(k) + d, d, 1) = gen.ground_truth[k].t;
  }
  return out;
}

TEST(ComponentAlignment, APieceMovedByAnyRigidMotionIsBroughtBackByTheMeasurementThatLinksIt) {
  TwoPieces t = two_noise_free_robots();
  ASSERT_GT(t.graph.measurements.size(), t.own + 1);  // more than one link
  ASSERT_LT(lifted_cost(t.graph, t.X, 0, t.graph.measurements.size()), 1e-18);
  const Eigen::Index w = t.graph.d + 1;
  std::mt19937 rng(11);
  for (bool reflect : {false, true}) {
    // Robot 1's piece in another frame of the lifted space, as drifting guesses leave it.
    Eigen::MatrixXd X = t.X;
    const Eigen::MatrixXd Q = random_orthogonal(kRank, rng, reflect);
    const Eigen::VectorXd shift = Eigen::VectorXd::LinSpaced(kRank, 30.0, -12.0);
    for (std::size_t k = t.graph.num_poses / 2; k < t.graph.num_poses; ++k) {
      auto P = X.middleCols(w * static_cast<Eigen::Index>(k), w);
      P = (Q * P).eval();
      P.col(t.graph.d) += shift;
    }
    const double own_cost = lifted_cost(t.graph, X, 0, t.own);
    EXPECT_LT(own_cost, 1e-16);
    EXPECT_GT(lifted_cost(t.graph, X, t.own, t.graph.measurements.size()), 1.0);

    // The pieces arrive apart, then the links.
    PoseGraph apart = t.graph;
    apart.measurements.resize(t.own);
    ComponentAlignment pieces;
    const ComponentMerges none = pieces.absorb(apart, X);
    EXPECT_EQ(none.merges, 0u);
    EXPECT_EQ(pieces.pieces(), 2u);
    const ComponentMerges linked = pieces.absorb(t.graph, X);
    EXPECT_EQ(linked.merges, 1u);  // the later links join one piece already
    EXPECT_EQ(linked.poses_moved, t.graph.num_poses / 2);
    EXPECT_EQ(pieces.pieces(), 1u);
    // Noise-free data: one link puts the moved piece back where the truth has it, so every
    // link, not only the first, has zero residual, and each piece's own residuals stayed zero.
    EXPECT_LT(lifted_cost(t.graph, X, 0, t.graph.measurements.size()), 1e-16) << reflect;
    // Still a point of the manifold: orthonormal rotation columns.
    for (std::size_t k = 0; k < t.graph.num_poses; ++k) {
      const auto Yk = X.middleCols(w * static_cast<Eigen::Index>(k), t.graph.d);
      EXPECT_LT((Yk.transpose() * Yk - Eigen::MatrixXd::Identity(t.graph.d, t.graph.d)).norm(),
                1e-12);
    }
  }
}

TEST(ComponentAlignment, MovesTheSmallerPieceAndLeavesTheOtherBitForBit) {
  TwoPieces t = two_noise_free_robots();
  const Eigen::Index w = t.graph.d + 1;
  // Robot 0 has grown further: only 20 of robot 1's poses are linked (a robot that just met).
  const std::size_t half = t.graph.num_poses / 2;
  PoseGraph own = t.graph, g = t.graph;
  own.measurements.clear();
  g.measurements.clear();
  for (std::size_t e = 0; e < t.graph.measurements.size(); ++e) {
    const Measurement& m = t.graph.measurements[e];
    if (m.i >= half + 20 || m.j >= half + 20) continue;
    if (e < t.own) own.measurements.push_back(m);
    g.measurements.push_back(m);
  }
  Eigen::MatrixXd X = t.X;
  std::mt19937 rng(5);
  const Eigen::MatrixXd Q = random_orthogonal(kRank, rng, false);
  for (std::size_t k = half; k < g.num_poses; ++k) {
    auto P = X.middleCols(w * static_cast<Eigen::Index>(k), w);
    P = (Q * P).eval();
  }
  ComponentAlignment pieces;
  const ComponentMerges apart = pieces.absorb(own, X);
  EXPECT_EQ(apart.merges, 0u);  // chains grow pose by pose: no two pieces met
  const Eigen::MatrixXd before = X;
  const ComponentMerges merges = pieces.absorb(g, X);
  EXPECT_EQ(merges.merges, 1u);
  EXPECT_EQ(merges.poses_moved, 20u);  // robot 1's linked poses; no pose of robot 0
  EXPECT_TRUE(X.leftCols(w * static_cast<Eigen::Index>(half)) ==
              before.leftCols(w * static_cast<Eigen::Index>(half)));
  EXPECT_LT(lifted_cost(g, X, 0, g.measurements.size()), 1e-16);
}

TEST(ComponentAlignment, TheLiftedRotationBetweenTwoFramesIsProperAndMapsOneOntoTheOther) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 4; ++trial) {
    const Eigen::MatrixXd A = random_orthogonal(kRank, rng, trial % 2 == 1).leftCols(3);
    const Eigen::MatrixXd B = random_orthogonal(kRank, rng, false).leftCols(3);
    const Eigen::MatrixXd Q = lifted_rotation_between(A, B);
    EXPECT_LT((Q * A - B).norm(), 1e-12);
    EXPECT_LT((Q.transpose() * Q - Eigen::MatrixXd::Identity(kRank, kRank)).norm(), 1e-12);
    EXPECT_NEAR(Q.determinant(), 1.0, 1e-12);
  }
}

}  // namespace
}  // namespace tessera
