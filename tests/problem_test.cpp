// The lifted problem: data matrix, block objective, derivatives, manifold operations.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cstring>
#include <random>
#include <stdexcept>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/data_matrix.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/problem/objective.hpp>
#include <tessera/problem/rounding.hpp>

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
  for (std::size_t i = 0; i < 40; ++i) EXPECT_EQ(X.col((d + 1) * i + d), A.col((d + 1) * i + d));
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
    P.set_neighbor_poses(gather_pose_columns(X, P.neighbors(), d));
    Eigen::MatrixXd Xb = gather_pose_columns(X, owned, d);
    sum += P.cost_share(Xb);
    // The block gradient equals the global gradient restricted to the block.
    Eigen::MatrixXd G = whole.euclidean_gradient(X);
    Eigen::MatrixXd Gb = P.euclidean_gradient(Xb);
    for (std::size_t k = 0; k < owned.size(); ++k)
      EXPECT_LT(
          (Gb.middleCols((d + 1) * k, d + 1) - G.middleCols((d + 1) * owned[k], d + 1)).norm(),
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

// The triplet assembly build_data_matrix replaced (duplicates summed in list order by
// setFromTriplets): the new pose-block assembly must give the same pattern (explicit zeros
// included, which the preconditioner's ordering sees) and the same values to the last bit.
SparseMatrix triplet_data_matrix(const std::vector<Measurement>& ms, int d, std::size_t n) {
  using Index = Eigen::Index;
  const Index w = d + 1;
  std::vector<Eigen::Triplet<double>> t;
  auto add = [&](Index r, Index c, double v) { t.emplace_back(r, c, v); };
  for (const Measurement& m : ms) {
    const Index ri = w * static_cast<Index>(m.i), rj = w * static_cast<Index>(m.j);
    const Index ti = ri + d, tj = rj + d;
    for (Index a = 0; a < d; ++a) {
      add(ri + a, ri + a, m.kappa);
      add(rj + a, rj + a, m.kappa);
      for (Index b = 0; b < d; ++b) {
        add(ri + a, rj + b, -m.kappa * m.R(a, b));
        add(rj + b, ri + a, -m.kappa * m.R(a, b));
      }
    }
    for (Index a = 0; a < d; ++a) {
      for (Index b = 0; b < d; ++b) add(ri + a, ri + b, m.tau * m.t(a) * m.t(b));
      add(ri + a, ti, m.tau * m.t(a));
      add(ti, ri + a, m.tau * m.t(a));
      add(ri + a, tj, -m.tau * m.t(a));
      add(tj, ri + a, -m.tau * m.t(a));
    }
    add(ti, ti, m.tau);
    add(tj, tj, m.tau);
    add(ti, tj, -m.tau);
    add(tj, ti, -m.tau);
  }
  SparseMatrix Q(w * static_cast<Index>(n), w * static_cast<Index>(n));
  Q.setFromTriplets(t.begin(), t.end());
  Q.makeCompressed();
  return Q;
}

void expect_identical(const SparseMatrix& A, const SparseMatrix& B) {
  ASSERT_EQ(A.rows(), B.rows());
  ASSERT_EQ(A.cols(), B.cols());
  ASSERT_EQ(A.nonZeros(), B.nonZeros());
  for (Eigen::Index c = 0; c < A.cols(); ++c) {
    SparseMatrix::InnerIterator a(A, c), b(B, c);
    for (; a && b; ++a, ++b) {
      ASSERT_EQ(a.row(), b.row()) << "column " << c;
      ASSERT_EQ(a.value(), b.value()) << "entry (" << a.row() << ", " << c << ")";  // bitwise
    }
    ASSERT_EQ(bool(a), bool(b)) << "column " << c;
  }
}

TEST_P(ProblemTest, DataMatrixEqualsTheTripletAssemblyExactly) {
  const int d = GetParam();
  auto g = test::random_pose_graph({d, 30, 25, 0.05, 0.1, 9});
  // Repeated pairs, in both directions, and a measurement with exact zeros in R and t.
  auto ms = g.measurements;
  for (std::size_t k = 0; k < 6; ++k) {
    Measurement m = ms[3 * k + 1];
    if (k % 2) std::swap(m.i, m.j);
    m.kappa *= 1.7;
    ms.push_back(m);
  }
  Measurement z = ms.front();
  z.R = Eigen::MatrixXd::Identity(d, d);
  z.t = Eigen::VectorXd::Zero(d);
  ms.push_back(z);
  const SparseMatrix ref = triplet_data_matrix(ms, d, g.num_poses);
  expect_identical(build_data_matrix(ms, d, g.num_poses), ref);

  // A block's Q_BB and Q_NB: the owned slots (in a scrambled order) first, then neighbours.
  std::vector<std::size_t> owned;
  for (std::size_t i = 0; i < g.num_poses; i += 3) owned.push_back(i);
  std::reverse(owned.begin() + 2, owned.end());
  std::vector<std::size_t> slot(g.num_poses, g.num_poses), neighbours;
  for (std::size_t s = 0; s < owned.size(); ++s) slot[owned[s]] = s;
  std::vector<const Measurement*> touching;
  for (const auto& m : ms) {
    const bool oi = slot[m.i] < g.num_poses, oj = slot[m.j] < g.num_poses;
    if (!oi && !oj) continue;
    touching.push_back(&m);
    if (!oi) neighbours.push_back(m.i);
    if (!oj) neighbours.push_back(m.j);
  }
  std::sort(neighbours.begin(), neighbours.end());
  neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
  ASSERT_FALSE(neighbours.empty());
  for (std::size_t k = 0; k < neighbours.size(); ++k) slot[neighbours[k]] = owned.size() + k;
  std::vector<std::size_t> si, sj;
  std::vector<Measurement> relabelled;
  for (const Measurement* m : touching) {
    si.push_back(slot[m->i]);
    sj.push_back(slot[m->j]);
    relabelled.push_back(*m);
    relabelled.back().i = si.back();
    relabelled.back().j = sj.back();
  }
  const std::size_t slots = owned.size() + neighbours.size();
  const SparseMatrix full = triplet_data_matrix(relabelled, d, slots);
  const auto blocks = build_data_matrix_blocks(touching, si, sj, d, slots, owned.size());
  const Eigen::Index nb = (d + 1) * static_cast<Eigen::Index>(owned.size());
  const Eigen::Index nn = (d + 1) * static_cast<Eigen::Index>(neighbours.size());
  SparseMatrix Qbb = full.topLeftCorner(nb, nb), Qnb = full.bottomLeftCorner(nn, nb);
  Qbb.makeCompressed();
  Qnb.makeCompressed();
  expect_identical(blocks.own, Qbb);
  expect_identical(blocks.neighbour, Qnb);
  expect_identical(BlockProblem(d, owned, ms).data_matrix(), Qbb);
}

// The cost at d rows (the agents' active rows: an unrolled, for d = 3 paired, edge kernel) is
// the general-rank loop's to the bit: the same point with two zero rows appended adds only exact
// zeros to an edge's sums, in the same order. One measurement a problem, so that each edge's
// term is compared alone (in a sum over many, a last-bit difference is rounded away).
TEST_P(ProblemTest, CostAtTheActiveRowsEqualsTheGeneralRankLoopBitForBit) {
  const int d = GetParam();
  auto g = test::random_pose_graph({d, 40, 30, 0.05, 0.1, 8});
  const LiftedManifold M(d, d, g.num_poses);
  std::srand(21);
  for (std::size_t e = 0; e < 200; ++e) {
    const BlockProblem P =
        BlockProblem::whole_graph(d, g.num_poses, {g.measurements[e % g.measurements.size()]});
    // Points off the manifold too: larger residuals, more rounding to tell orders apart.
    const Eigen::MatrixXd X = random_point(M, 100 + e) + 0.3 * Eigen::MatrixXd::Random(d, M.cols());
    Eigen::MatrixXd Xp = Eigen::MatrixXd::Zero(d + 2, X.cols());
    Xp.topRows(d) = X;
    const double f = P.cost(X), f_padded = P.cost(Xp);
    EXPECT_GT(f, 0.0);
    EXPECT_EQ(f, f_padded) << e;
  }
}

// The general SVD route project_to_rotation took for every size: its 2 x 2 and 3 x 3 blocks
// now go through fixed-size matrices, and the chordal start and the rounding must not move a bit.
Eigen::MatrixXd rotation_by_dynamic_svd(const Eigen::MatrixXd& A) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::MatrixXd U = svd.matrixU();
  const Eigen::MatrixXd& V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0) U.col(U.cols() - 1) *= -1.0;
  return U * V.transpose();
}

TEST_P(ProblemTest, ProjectToRotationIsTheGeneralSvdsResultBitForBit) {
  const int d = GetParam();
  std::mt19937 gen(11);
  std::normal_distribution<double> normal;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> into(d, d);
  for (int k = 0; k < 20000; ++k) {
    Eigen::MatrixXd A(d, d);
    for (Eigen::Index e = 0; e < A.size(); ++e) A.data()[e] = normal(gen);
    // Half near a rotation or a reflection, as the chordal start's and the rounding's blocks are.
    if (k % 2 == 1) A = rotation_by_dynamic_svd(A) + 1e-3 * A;
    if (k % 4 == 3) A.row(0) *= -1.0;
    const Eigen::MatrixXd expected = rotation_by_dynamic_svd(A);
    const Eigen::MatrixXd got = project_to_rotation(A);
    ASSERT_EQ(got.rows(), d);
    ASSERT_EQ(got.cols(), d);
    ASSERT_EQ(0, std::memcmp(got.data(), expected.data(), sizeof(double) * d * d)) << "k = " << k;
    project_to_rotation(A, into);
    ASSERT_EQ(0, std::memcmp(into.data(), expected.data(), sizeof(double) * d * d)) << "k = " << k;
    EXPECT_GT(determinant_of(got), 0.0);
    EXPECT_EQ(determinant_of(A) < 0, A.determinant() < 0) << "k = " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(Dimensions, ProblemTest, ::testing::Values(2, 3));

TEST(ProjectToRotation, AnotherSizeTakesTheGeneralSvdAndAMismatchedOutputThrows) {
  std::srand(5);
  const Eigen::MatrixXd A = Eigen::MatrixXd::Random(5, 5);
  const Eigen::MatrixXd R = project_to_rotation(A);
  EXPECT_EQ(0, std::memcmp(R.data(), rotation_by_dynamic_svd(A).data(), sizeof(double) * 25));
  EXPECT_NEAR(determinant_of(R), 1.0, 1e-12);
  Eigen::MatrixXd wrong(3, 3);
  EXPECT_THROW(project_to_rotation(Eigen::MatrixXd::Identity(2, 2), wrong), std::invalid_argument);
  EXPECT_THROW(project_to_rotation(Eigen::MatrixXd::Identity(2, 3), wrong), std::invalid_argument);
}

TEST(PoseColumns, AGatheredBlockHoldsItsPosesInIdOrderAndScattersBackIntoThemOnly) {
  const int d = 2;
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(4, 3 * 5);  // rank 4, 5 poses
  const std::vector<std::size_t> ids{3, 0};
  const Eigen::MatrixXd Y = gather_pose_columns(X, ids, d);
  ASSERT_EQ(Y.rows(), 4);
  ASSERT_EQ(Y.cols(), 6);
  EXPECT_EQ(Y.leftCols(3), X.middleCols(9, 3));
  EXPECT_EQ(Y.rightCols(3), X.leftCols(3));

  Eigen::MatrixXd Z = Eigen::MatrixXd::Zero(4, 15);
  scatter_pose_columns(Y, ids, d, Z);
  EXPECT_EQ(Z.middleCols(9, 3), X.middleCols(9, 3));
  EXPECT_EQ(Z.leftCols(3), X.leftCols(3));
  EXPECT_TRUE(Z.middleCols(3, 6).isZero(0.0));  // poses 1 and 2: not in `ids`
  EXPECT_TRUE(Z.rightCols(3).isZero(0.0));      // pose 4
}

TEST(PoseColumns, AnIdPastTheLastPoseOrABlockOfAnotherSizeThrows) {
  const int d = 3;
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(5, 4 * 3);
  EXPECT_THROW(gather_pose_columns(X, {1, 3}, d), std::out_of_range);
  EXPECT_THROW(scatter_pose_columns(Eigen::MatrixXd::Zero(5, 8), {0, 3}, d, X), std::out_of_range);
  // One pose short, or another rank than X's.
  EXPECT_THROW(scatter_pose_columns(Eigen::MatrixXd::Zero(5, 4), {0, 1}, d, X),
               std::invalid_argument);
  EXPECT_THROW(scatter_pose_columns(Eigen::MatrixXd::Zero(4, 8), {0, 1}, d, X),
               std::invalid_argument);
  EXPECT_TRUE(X.isZero(0.0));  // nothing written by a call that throws on its sizes
}

}  // namespace
}  // namespace tessera
