// The hand-written derivative kernels (problem/pose_kernels.hpp) against the plain Eigen /
// LiftedManifold expressions they replace, for every rank with a fixed-size path and one without.

#include <gtest/gtest.h>

#include <random>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/pose_block_matrix.hpp>
#include <tessera/problem/pose_kernels.hpp>
#include <vector>

#include "random_graph.hpp"
#include "util/avx_kernels.hpp"

namespace tessera {
namespace {

Eigen::MatrixXd random_point(const LiftedManifold& M, unsigned seed) {
  std::srand(seed);
  return M.project(Eigen::MatrixXd::Random(M.rank(), M.cols()));
}

double max_abs(const Eigen::MatrixXd& A) {
  return A.cwiseAbs().maxCoeff();
}

class PoseKernels : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(PoseKernels, DenseTimesSparseMatchesEigen) {
  const auto [d, r] = GetParam();
  auto g = test::random_pose_graph({d, 30, 20, 0.05, 0.1, 9});
  const BlockProblem P = BlockProblem::whole_graph(d, g.num_poses, g.measurements);
  const SparseMatrix& Q = P.data_matrix();
  std::srand(3);
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(r, Q.rows());
  Eigen::MatrixXd out;
  scaled_dense_times_sparse(X, Q, 2.0, out);
  const Eigen::MatrixXd ref = 2.0 * (X * Q);
  ASSERT_EQ(out.rows(), ref.rows());
  ASSERT_EQ(out.cols(), ref.cols());
  EXPECT_LE(max_abs(out - ref), 1e-12 * max_abs(ref));
  // A rectangular, uncompressed right factor (the cut-edge block Q_NB has this shape).
  SparseMatrix R = Q.leftCols(Q.cols() / 2);
  R.uncompress();
  R.coeffRef(0, 0) += 1.0;
  scaled_dense_times_sparse(X, R, -0.5, out);
  const Eigen::MatrixXd ref2 = -0.5 * (X * R);
  ASSERT_EQ(out.cols(), ref2.cols());
  EXPECT_LE(max_abs(out - ref2), 1e-12 * max_abs(ref2));
}

// The agents' products read Q_BB by dense pose blocks (entries the sparse form lacks are explicit
// zeros there): the same values as the sparse kernel to the last bit, for every row count
// (one row: the certificate's LOBPCG vectors).
TEST_P(PoseKernels, PoseBlockProductIsBitIdenticalToTheSparseOne) {
  const auto [d, r] = GetParam();
  auto g = test::random_pose_graph({d, 30, 20, 0.05, 0.1, 9});
  const BlockProblem whole = BlockProblem::whole_graph(d, g.num_poses, g.measurements);
  const SparseMatrix& Q = whole.data_matrix();
  const PoseBlockMatrix B(Q, d + 1);
  EXPECT_LT(B.num_blocks(), static_cast<std::size_t>(Q.nonZeros()));  // one index a block
  std::srand(4);
  for (int rows : {1, r, d}) {
    const Eigen::MatrixXd X = Eigen::MatrixXd::Random(rows, Q.rows());
    Eigen::MatrixXd sparse, blocks;
    scaled_dense_times_sparse(X, Q, 2.0, sparse);
    B.times(X, 2.0, blocks);
    EXPECT_TRUE(blocks == sparse) << d << " " << rows;
    // The baseline (SSE2) kernels as well where the AVX ones ran.
    const bool avx = set_avx_kernels(false);
    B.times(X, 2.0, blocks);
    set_avx_kernels(avx);
    EXPECT_TRUE(blocks == sparse) << d << " " << rows << " without AVX";
  }
  // A block problem's gradient and Hessian products, with and without the pose blocks.
  std::vector<std::size_t> own;
  for (std::size_t i = 0; i < g.num_poses; i += 2) own.push_back(i);
  BlockProblem plain(d, own, g.measurements), by_blocks(d, own, g.measurements);
  by_blocks.use_pose_blocks();
  EXPECT_GT(by_blocks.pose_blocks_bytes(), 0u);
  const LiftedManifold M(r, d, own.size());
  const Eigen::MatrixXd X = random_point(M, 7);
  const Eigen::MatrixXd Xn = Eigen::MatrixXd::Random(r, (d + 1) * plain.num_neighbors());
  plain.set_neighbor_poses(Xn);
  by_blocks.set_neighbor_poses(Xn);
  const Eigen::MatrixXd G = plain.euclidean_gradient(X);
  EXPECT_TRUE(by_blocks.euclidean_gradient(X) == G);
  const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(r, M.cols()));
  EXPECT_TRUE(by_blocks.hessian_vector(X, G, V) == plain.hessian_vector(X, G, V));
}

TEST_P(PoseKernels, HessianProjectionMatchesManifoldOperations) {
  const auto [d, r] = GetParam();
  const LiftedManifold M(r, d, 17);
  const Eigen::MatrixXd X = random_point(M, 5);
  std::srand(6);
  const Eigen::MatrixXd G = Eigen::MatrixXd::Random(r, M.cols());
  const Eigen::MatrixXd V = M.tangent_project(X, Eigen::MatrixXd::Random(r, M.cols()));
  const Eigen::MatrixXd H0 = Eigen::MatrixXd::Random(r, M.cols());
  Eigen::MatrixXd H = H0;
  apply_hessian_projection(X, G, V, d, H);
  const Eigen::MatrixXd ref = M.tangent_project(X, H0) - M.weingarten_term(X, G, V);
  EXPECT_LE(max_abs(H - ref), 1e-12 * max_abs(ref));
}

TEST(PoseKernelsShapes, RejectMismatchedOperands) {
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(3, 8), out;
  SparseMatrix Q(9, 9);
  EXPECT_THROW(scaled_dense_times_sparse(X, Q, 1.0, out), std::invalid_argument);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, 6);
  EXPECT_THROW(apply_hessian_projection(X, X, X, 2, H), std::invalid_argument);
  EXPECT_THROW(apply_hessian_projection(X, X, X, 4, X), std::invalid_argument);
  EXPECT_THROW(PoseBlockMatrix(Q, 4), std::invalid_argument);  // 9 is not a multiple of 4
  Eigen::MatrixXd Y = Eigen::MatrixXd::Zero(3, 6);
  EXPECT_THROW(PoseBlockMatrix(Q, 3).times(Y, 1.0, out), std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(RanksAndDimensions, PoseKernels,
                         ::testing::Combine(::testing::Values(2, 3), ::testing::Values(3, 5, 7)));

}  // namespace
}  // namespace tessera
