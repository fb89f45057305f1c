// The tangent preconditioner's own triangular solves (solvers/ldl_chain_solve.hpp) give exactly
// cholmod_solve2's result, bit for bit, on simplicial LDL^T factors of pose-block matrices:
// with a pose-contiguous ordering (the preconditioner's), with CHOLMOD's scalar AMD ordering,
// and after a supernodal factor's conversion (explicit zeros in the pattern); supernodal
// factors are refused. Both kernel sets (AVX where the CPU has it, and SSE2) are checked.

#include "solvers/ldl_chain_solve.hpp"

#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <cstring>
#include <numeric>
#include <random>
#include <vector>

#include "solvers/tangent_factor.hpp"
#include "util/avx_kernels.hpp"

namespace tessera {
namespace {

// A symmetric positive definite matrix of m x m pose blocks of size p: a chain of poses plus
// random extra pairs, dense random blocks, a dominant diagonal.
SparseMatrix pose_block_matrix(int m, int p, int extra_pairs, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> pose(0, m - 1);
  std::vector<std::pair<int, int>> pairs;
  for (int i = 1; i < m; ++i) pairs.emplace_back(i, i - 1);
  for (int e = 0; e < extra_pairs; ++e) {
    const int a = pose(rng), b = pose(rng);
    if (a != b) pairs.emplace_back(std::max(a, b), std::min(a, b));
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  std::vector<Eigen::Triplet<double>> t;
  for (const auto& [a, b] : pairs)
    for (int r = 0; r < p; ++r)
      for (int c = 0; c < p; ++c) {
        const double v = value(rng);
        t.emplace_back(a * p + r, b * p + c, v);
        t.emplace_back(b * p + c, a * p + r, v);
      }
  for (int i = 0; i < m; ++i)
    for (int r = 0; r < p; ++r)
      for (int c = 0; c <= r; ++c) {
        const double v = r == c ? 4.0 * p * 8 + value(rng) : value(rng);
        t.emplace_back(i * p + r, i * p + c, v);
        if (r != c) t.emplace_back(i * p + c, i * p + r, v);
      }
  SparseMatrix A(m * p, m * p);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

std::vector<int> pose_contiguous_order(int m, int p, unsigned seed) {
  std::vector<int> poses(static_cast<std::size_t>(m));
  std::iota(poses.begin(), poses.end(), 0);
  std::shuffle(poses.begin(), poses.end(), std::mt19937(seed));
  std::vector<int> order;
  for (int i : poses)
    for (int c = 0; c < p; ++c) order.push_back(i * p + c);
  return order;
}

// Solves with CHOLMOD and with LdlChainSolve for a few right-hand sides; true when every
// result is bit-identical.
void expect_same_bits(CholmodLdlt& llt, Eigen::Index n) {
  LdlChainSolve chain;
  ASSERT_TRUE(chain.build(llt.factor()));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd b(n);
    for (Eigen::Index k = 0; k < n; ++k) b(k) = value(rng);
    cholmod_dense rhs = cholmod_dense_view(b);
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, llt.factor(), &rhs, &llt.cholmod());
    ASSERT_NE(x, nullptr);
    Eigen::VectorXd mine(n);
    chain.solve(llt.factor(), b.data(), mine.data());
    EXPECT_EQ(std::memcmp(mine.data(), x->x, static_cast<std::size_t>(n) * sizeof(double)), 0);
    // The baseline (SSE2) kernels as well where the AVX ones ran.
    const bool avx = set_avx_kernels(false);
    chain.solve(llt.factor(), b.data(), mine.data());
    set_avx_kernels(avx);
    EXPECT_EQ(std::memcmp(mine.data(), x->x, static_cast<std::size_t>(n) * sizeof(double)), 0)
        << "without AVX";
    cholmod_free_dense(&x, &llt.cholmod());
  }
}

TEST(LdlChainSolve, MatchesCholmodBitForBitWithPoseContiguousOrdering) {
  // Runs of 3, 6 and 7 rows: every remainder after the four-row registers.
  for (int p : {3, 6, 7}) {
    SparseMatrix A = pose_block_matrix(60, p, 50, 11u + static_cast<unsigned>(p));
    std::vector<int> order = pose_contiguous_order(60, p, 5);
    CholmodLdlt llt;
    llt.setMode(Eigen::CholmodLDLt);
    llt.cholmod().postorder = 1;
    llt.analyze_with_ordering(A, order);
    llt.factorize(A);
    ASSERT_EQ(llt.info(), Eigen::Success);
    expect_same_bits(llt, A.rows());
  }
}

TEST(LdlChainSolve, MatchesCholmodBitForBitWithScalarAmdOrdering) {
  for (int p : {3, 6}) {
    SparseMatrix A = pose_block_matrix(80, p, 70, 23u + static_cast<unsigned>(p));
    CholmodLdlt llt;
    llt.setMode(Eigen::CholmodLDLt);
    llt.compute(A);
    ASSERT_EQ(llt.info(), Eigen::Success);
    expect_same_bits(llt, A.rows());
  }
}

TEST(LdlChainSolve, MatchesCholmodBitForBitAfterSupernodalConversion) {
  SparseMatrix A = pose_block_matrix(120, 6, 150, 31u);
  std::vector<int> order = pose_contiguous_order(120, 6, 9);
  CholmodLdlt llt;
  llt.setMode(Eigen::CholmodSupernodalLLt);
  llt.cholmod().postorder = 1;
  llt.analyze_with_ordering(A, order);
  llt.factorize(A);
  ASSERT_EQ(llt.info(), Eigen::Success);
  LdlChainSolve refused;
  EXPECT_FALSE(refused.build(llt.factor()));  // supernodal: left to CHOLMOD
  ASSERT_TRUE(cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, llt.factor(), &llt.cholmod()));
  expect_same_bits(llt, A.rows());
}

// With split dots (four partial sums): the AVX and SSE2 kernels give the same bits, and both
// solve A x = b to round-off. Runs of every length mod 4 (leftover rows 0-3), from pose-
// contiguous orderings with p = 3, 5, 6, 7 and from CHOLMOD's scalar AMD ordering.
void expect_split_dots_agree(CholmodLdlt& llt, const SparseMatrix& A) {
  LdlChainSolve chain;
  ASSERT_TRUE(chain.build(llt.factor()));
  chain.set_split_dots(true);
  const Eigen::Index n = A.rows();
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd b(n);
    for (Eigen::Index k = 0; k < n; ++k) b(k) = value(rng);
    Eigen::VectorXd mine(n), baseline(n), sequential(n);
    chain.solve(llt.factor(), b.data(), mine.data());
    const bool avx = set_avx_kernels(false);
    chain.solve(llt.factor(), b.data(), baseline.data());
    set_avx_kernels(avx);
    EXPECT_EQ(
        std::memcmp(mine.data(), baseline.data(), static_cast<std::size_t>(n) * sizeof(double)), 0);
    chain.set_split_dots(false);
    chain.solve(llt.factor(), b.data(), sequential.data());
    chain.set_split_dots(true);
    EXPECT_NE(
        std::memcmp(mine.data(), sequential.data(), static_cast<std::size_t>(n) * sizeof(double)),
        0);  // the partial sums did run
    EXPECT_LT((A * mine - b).norm(), 1e-12 * b.norm());
    EXPECT_LT((mine - sequential).norm(), 1e-12 * sequential.norm());
  }
}

TEST(LdlChainSolve, SplitDotsGiveTheSameBitsWithAvxAndSse2) {
  for (int p : {3, 5, 6, 7}) {
    SparseMatrix A = pose_block_matrix(60, p, 50, 41u + static_cast<unsigned>(p));
    std::vector<int> order = pose_contiguous_order(60, p, 3);
    CholmodLdlt llt;
    llt.setMode(Eigen::CholmodLDLt);
    llt.cholmod().postorder = 1;
    llt.analyze_with_ordering(A, order);
    llt.factorize(A);
    ASSERT_EQ(llt.info(), Eigen::Success);
    expect_split_dots_agree(llt, A);
  }
  SparseMatrix A = pose_block_matrix(80, 6, 70, 53u);
  CholmodLdlt llt;
  llt.setMode(Eigen::CholmodLDLt);
  llt.compute(A);
  ASSERT_EQ(llt.info(), Eigen::Success);
  expect_split_dots_agree(llt, A);
}

}  // namespace
}  // namespace tessera
