// The kernels that take several poses or measurements at once, one a vector lane
// (manifold/pose_lanes.hpp, problem/edge_lanes.hpp), against the one-by-one code they stand for:
// the same bits, with AVX (four lanes) and without (two), for groups the lanes take and groups they
// hand back.

#include "manifold/pose_lanes.hpp"

#include <gtest/gtest.h>

#include <tessera/distributed/momentum.hpp>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/pose_kernels.hpp>
#include <vector>

#include "random_graph.hpp"
#include "solvers/tangent_coordinates.hpp"
#include "util/avx_kernels.hpp"

namespace tessera {
namespace {

// n 3D poses at rank r near the manifold, pose i at distance ~offsets[i % size] from it. With
// r = 5 the rows 3-4 are zero (a lifted start's) except in the poses listed in `full_rows`.
Eigen::MatrixXd poses_near_manifold(int r, int n, const std::vector<double>& offsets,
                                    const std::vector<int>& full_rows, unsigned seed) {
  std::srand(seed);
  const LiftedManifold M3(3, 3, n);
  const Eigen::MatrixXd Y = M3.project(Eigen::MatrixXd::Random(3, 4 * n));
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(r, 4 * n);
  for (int i = 0; i < n; ++i) {
    const double t = offsets[static_cast<std::size_t>(i) % offsets.size()];
    A.block(0, 4 * i, 3, 4) = Y.middleCols(4 * i, 4) + t * Eigen::MatrixXd::Random(3, 4);
  }
  for (int i : full_rows) A.block(3, 4 * i, r - 3, 4) = 1e-3 * Eigen::MatrixXd::Random(r - 3, 4);
  return A;
}

// Proj_M of every pose on its own: one pose is fewer than any group, so the pose-by-pose code.
Eigen::MatrixXd project_pose_by_pose(const Eigen::MatrixXd& A) {
  Eigen::MatrixXd out = A;
  const LiftedManifold one(static_cast<int>(A.rows()), 3, 1);
  for (Eigen::Index i = 0; i < A.cols() / 4; ++i)
    out.middleCols(4 * i, 4) = project_to_manifold(one, A.middleCols(4 * i, 4));
  return out;
}

class PoseLanes : public ::testing::TestWithParam<bool> {
 protected:
  void SetUp() override { avx_before_ = set_avx_kernels(GetParam()); }
  void TearDown() override { set_avx_kernels(avx_before_); }
  bool avx_before_ = false;
};

TEST_P(PoseLanes, ProjectionInLanesIsBitIdenticalToPoseByPose) {
  // Offsets below 1e-9 (the series' first term), within the series (1e-7, 1e-5), and beyond it
  // (Newton-Schulz, the eigen-decomposition): groups of each kind and mixed ones, plus the
  // leftover poses after the last whole group.
  const std::vector<std::vector<double>> mixes = {
      {1e-12, 1e-7, 1e-5, 3e-11}, {1e-7}, {1e-12, 1e-7, 1e-3, 1e-6, 1e-8, 0.7, 1e-6}};
  for (int r : {3, 5})
    for (std::size_t m = 0; m < mixes.size(); ++m) {
      const int n = 23;
      const std::vector<int> full = r == 5 ? std::vector<int>{5, 14} : std::vector<int>{};
      const Eigen::MatrixXd A = poses_near_manifold(r, n, mixes[m], full, 17 + m);
      const LiftedManifold M(r, 3, n);
      EXPECT_TRUE(project_to_manifold(M, A) == project_pose_by_pose(A)) << r << " " << m;
      // The momentum blends take the same path.
      const MomentumCoefficients c{0.25, 1.0, 0.0};
      const Eigen::MatrixXd Y = poses_near_manifold(r, n, {0.0}, {}, 3);
      EXPECT_TRUE(extrapolate(M, c, Y, A) == project_pose_by_pose(0.25 * A + 0.75 * Y))
          << r << " " << m;
      const MomentumCoefficients c2{0.0, 0.875, 0.3};
      const Eigen::MatrixXd Yn = poses_near_manifold(r, n, {1e-6}, {}, 4);
      EXPECT_TRUE(momentum_update(M, c2, A, Y, Yn) ==
                  project_pose_by_pose((0.875 * A + 0.125 * Y) + 0.3 * (Yn - Y)))
          << r << " " << m;
    }
}

TEST_P(PoseLanes, AGroupWithAPoseOutsideTheSeriesIsHandedBackUntouched) {
  const int lanes = pose_lanes();
  EXPECT_EQ(lanes, avx_kernels_enabled() ? 4 : 2);
  for (int r : {3, 5}) {
    Eigen::MatrixXd A = poses_near_manifold(r, lanes, {1e-6}, {}, 5);
    const Eigen::MatrixXd expected = project_pose_by_pose(A);
    Eigen::MatrixXd B = A;
    B(1, 4 * (lanes - 1)) += 1e-3;  // the last pose: Newton-Schulz's
    const Eigen::MatrixXd B0 = B;
    EXPECT_FALSE(polar_in_lanes(B.data(), lanes, r));
    EXPECT_TRUE(B == B0);
    ASSERT_TRUE(polar_in_lanes(A.data(), lanes, r));
    EXPECT_TRUE(A == expected) << r;
  }
}

// The agents' tangent projections and Hessian projections at r = 3 (their active rows): in
// groups, with the leftover poses after the last group pose by pose.
TEST_P(PoseLanes, TangentAndHessianProjectionsInLanesAreBitIdenticalToPoseByPose) {
  const int n = 23;
  const LiftedManifold M(3, 3, n), one(3, 3, 1);
  const Eigen::MatrixXd X = poses_near_manifold(3, n, {0.0}, {}, 8);
  std::srand(9);
  const Eigen::MatrixXd V = Eigen::MatrixXd::Random(3, 4 * n);
  const Eigen::MatrixXd G = Eigen::MatrixXd::Random(3, 4 * n);
  const Eigen::MatrixXd H0 = Eigen::MatrixXd::Random(3, 4 * n);
  Eigen::MatrixXd projected(3, 4 * n), H = H0, H_each = H0;
  for (int i = 0; i < n; ++i) {
    projected.middleCols(4 * i, 4) =
        one.tangent_project(X.middleCols(4 * i, 4), V.middleCols(4 * i, 4));
    Eigen::MatrixXd h = H0.middleCols(4 * i, 4);
    apply_hessian_projection(X.middleCols(4 * i, 4), G.middleCols(4 * i, 4), V.middleCols(4 * i, 4),
                             3, h);
    H_each.middleCols(4 * i, 4) = h;
  }
  EXPECT_TRUE(M.tangent_project(X, V) == projected);
  EXPECT_TRUE(M.tangent_project(X, Eigen::MatrixXd(V)) == projected);  // in place
  apply_hessian_projection(X, G, V, 3, H);
  EXPECT_TRUE(H == H_each);
}

// The tangent preconditioner's coordinate maps J^T V and J c (solvers/tangent_coordinates.hpp):
// in groups, against one pose a call.
TEST_P(PoseLanes, TangentCoordinateMapsInLanesAreBitIdenticalToPoseByPose) {
  const int n = 23;
  const Eigen::MatrixXd X = poses_near_manifold(3, n, {0.0}, {}, 10);
  std::srand(11);
  const Eigen::MatrixXd V = Eigen::MatrixXd::Random(3, 4 * n);
  const Eigen::VectorXd c = Eigen::VectorXd::Random(6 * n);
  Eigen::VectorXd b(6 * n), b_each(6 * n);
  Eigen::MatrixXd Z(3, 4 * n), Z_each(3, 4 * n);
  tangent_coordinates<3>(X.data(), V.data(), n, b.data());
  tangent_vector<3>(X.data(), c.data(), n, Z.data());
  for (int i = 0; i < n; ++i) {
    tangent_coordinates<3>(X.data() + 12 * i, V.data() + 12 * i, 1, b_each.data() + 6 * i);
    tangent_vector<3>(X.data() + 12 * i, c.data() + 6 * i, 1, Z_each.data() + 12 * i);
  }
  EXPECT_TRUE(b == b_each);
  EXPECT_TRUE(Z == Z_each);
}

// The cost at a 3D block's 3 active rows adds its measurements' terms computed in groups (the
// leftover ones one by one); at rank 5 (rows 3-4 zero) every term comes from the general
// per-measurement loop, which gives each term's bits (ProblemTest): the same sums to the bit.
TEST_P(PoseLanes, CostInLanesIsBitIdenticalToTheGeneralLoop) {
  auto g = test::random_pose_graph({3, 40, 31, 0.05, 0.1, 8});
  std::vector<std::size_t> own;
  for (std::size_t i = 0; i < g.num_poses; i += 3) own.push_back(i);
  BlockProblem whole = BlockProblem::whole_graph(3, g.num_poses, g.measurements);
  BlockProblem block(3, own, g.measurements);
  std::srand(12);
  const Eigen::MatrixXd Xn = Eigen::MatrixXd::Random(3, 4 * block.num_neighbors());
  Eigen::MatrixXd Xn5 = Eigen::MatrixXd::Zero(5, Xn.cols());
  Xn5.topRows(3) = Xn;
  for (BlockProblem* P : {&whole, &block}) {
    const Eigen::Index n = P == &whole ? static_cast<Eigen::Index>(g.num_poses)
                                       : static_cast<Eigen::Index>(own.size());
    // Off the manifold too: larger residuals, more rounding to tell orders apart.
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(3, 4 * n);
    Eigen::MatrixXd X5 = Eigen::MatrixXd::Zero(5, X.cols());
    X5.topRows(3) = X;
    double share = 0.0, share5 = 0.0;
    if (P == &block) P->set_neighbor_poses(Xn);
    const double f = P->cost(X, &share);
    if (P == &block) P->set_neighbor_poses(Xn5);
    const double f5 = P->cost(X5, &share5);
    EXPECT_EQ(f, f5);
    EXPECT_EQ(share, share5);
  }
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutAvx, PoseLanes, ::testing::Bool());

}  // namespace
}  // namespace tessera
