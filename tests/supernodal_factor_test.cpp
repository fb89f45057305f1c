// SupernodalFactor: the factor of A + shift I on a pattern analysed once, against dense LL^T.

#include "solvers/supernodal_factor.hpp"

#include <gtest/gtest.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <random>
#include <vector>

namespace tessera {
namespace {

// Lower triangle of a symmetric matrix with dense diagonal blocks joined by sparse couplings
// (the shape of the refinement's interface matrix), explicit zeros kept.
SparseMatrix lower_of(const Eigen::MatrixXd& dense, const std::vector<std::pair<int, int>>& zeros) {
  std::vector<Eigen::Triplet<double>> t;
  for (Eigen::Index j = 0; j < dense.cols(); ++j)
    for (Eigen::Index i = j; i < dense.rows(); ++i)
      if (dense(i, j) != 0.0) t.emplace_back(i, j, dense(i, j));
  for (const auto& z : zeros) t.emplace_back(z.first, z.second, 0.0);
  SparseMatrix out(dense.rows(), dense.cols());
  out.setFromTriplets(t.begin(), t.end());
  return out;
}

// Blocks of `block` coordinates, each B_k B_k^T with B_k random block x (block + 2) (dense,
// positive definite), and couplings between consecutive blocks' last and first coordinates;
// `scale` multiplies the couplings.
Eigen::MatrixXd blocky(int blocks, int block, double scale, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  const int n = blocks * block;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < blocks; ++k) {
    Eigen::MatrixXd B(block, block + 2);
    for (Eigen::Index i = 0; i < B.size(); ++i) B.data()[i] = g(rng);
    A.block(k * block, k * block, block, block) = B * B.transpose();
  }
  for (int k = 0; k + 1 < blocks; ++k) {
    const int i = k * block + block - 1, j = (k + 1) * block;
    const double c = scale * g(rng);
    A(i, j) += c;
    A(j, i) += c;
  }
  return A;
}

TEST(SupernodalFactor, SolvesLikeDenseCholeskyOfTheShiftedMatrix) {
  const Eigen::MatrixXd A = blocky(5, 12, 0.5, 1);
  SupernodalFactor f;
  ASSERT_TRUE(f.factor(lower_of(A, {}), 1e-3));
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0), x;
  f.solve(b, x);
  const Eigen::MatrixXd shifted = A + 1e-3 * Eigen::MatrixXd::Identity(A.rows(), A.cols());
  const Eigen::VectorXd want = shifted.llt().solve(b);
  EXPECT_LT((x - want).norm(), 1e-9 * want.norm());
  EXPECT_GT(f.factor_entries(), 0u);
  EXPECT_GT(f.factor_flops(), 0.0);
}

TEST(SupernodalFactor, SamePatternIsAnalysedOnceAcrossValuesAndShifts) {
  const std::vector<std::pair<int, int>> zeros = {{30, 2}, {59, 0}};
  SupernodalFactor f;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Eigen::MatrixXd A = blocky(5, 12, 0.5, seed);
    ASSERT_TRUE(f.factor(lower_of(A, zeros), 1e-2));
    ASSERT_TRUE(f.factor(lower_of(A, zeros), 1e-4));
    Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows()), x;
    f.solve(b, x);
    const Eigen::VectorXd want =
        (A + 1e-4 * Eigen::MatrixXd::Identity(A.rows(), A.cols())).llt().solve(b);
    EXPECT_LT((x - want).norm(), 1e-8 * want.norm()) << "seed " << seed;
  }
  EXPECT_EQ(f.analyses(), 1);
  // Another pattern (one more explicit entry) is analysed anew.
  const Eigen::MatrixXd A = blocky(5, 12, 0.5, 4);
  ASSERT_TRUE(f.factor(lower_of(A, {{30, 2}}), 1e-2));
  EXPECT_EQ(f.analyses(), 2);
}

TEST(SupernodalFactor, IndefiniteMatrixFailsThenALargerShiftOnTheSameAnalysisSolves) {
  Eigen::MatrixXd A = blocky(4, 10, 0.5, 7);
  // An indefinite direction of size -0.1 in the third block.
  A(25, 25) -= A(25, 25) + 0.1;
  SupernodalFactor f;
  const SparseMatrix lower = lower_of(A, {});
  EXPECT_FALSE(f.factor(lower, 1e-6));
  EXPECT_THROW(
      {
        Eigen::VectorXd x;
        f.solve(Eigen::VectorXd::Ones(A.rows()), x);
      },
      std::logic_error);
  const double big = 1.0 - Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues()(0);
  ASSERT_TRUE(f.factor(lower, big));
  EXPECT_EQ(f.analyses(), 1);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), 1.0, 3.0), x;
  f.solve(b, x);
  const Eigen::VectorXd want =
      (A + big * Eigen::MatrixXd::Identity(A.rows(), A.cols())).llt().solve(b);
  EXPECT_LT((x - want).norm(), 1e-9 * want.norm());
}

// With the caller's order (an interior first, an interface last): L's trailing block gives the
// interface's Schur complement, and the L, L^T solves the substructured solve of A x = b.
TEST(SupernodalFactor, GivenOrderKeepsTheInterfaceLastForItsSchurComplement) {
  const Eigen::MatrixXd A =
      blocky(3, 10, 0.5, 3) + 0.1 * Eigen::MatrixXd::Identity(30, 30);  // positive definite
  const Eigen::Index nI = 22, nG = 8;
  SupernodalFactor f(SupernodalFactor::Ordering::kGiven);
  ASSERT_TRUE(f.factor(lower_of(A, {})));
  const Eigen::MatrixXd Lgg = f.trailing_block(nI);
  ASSERT_EQ(Lgg.rows(), nG);
  const Eigen::MatrixXd schur =
      A.bottomRightCorner(nG, nG) -
      A.bottomLeftCorner(nG, nI) * A.topLeftCorner(nI, nI).llt().solve(A.topRightCorner(nI, nG));
  EXPECT_LT((Lgg * Lgg.transpose() - schur).norm(), 1e-10 * schur.norm());
  // x = L^-T L^-1 b.
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(30, -2.0, 1.0);
  const Eigen::VectorXd want = A.llt().solve(v);
  f.solve_l(v);
  f.solve_lt(v);
  EXPECT_LT((v - want).norm(), 1e-9 * want.norm());
  // The AMD ordering has no trailing block to give.
  SupernodalFactor amd;
  ASSERT_TRUE(amd.factor(lower_of(A, {})));
  EXPECT_THROW(amd.trailing_block(nI), std::logic_error);
}

TEST(SupernodalFactor, ImportedValuesSolveToTheBitLikeTheFactorTheyCameFrom) {
  // Agent 0 factors the refinement's interface matrix and sends values(); an agent whose own
  // factor was analysed on the same pattern (an earlier point's matrix) takes them and solves
  // with exactly the bits agent 0's factor gives.
  const Eigen::MatrixXd A = blocky(5, 12, 0.5, 1), B = blocky(5, 12, 0.5, 2);
  SupernodalFactor sender, receiver, fresh;
  ASSERT_TRUE(sender.factor(lower_of(A, {}), 1e-3));
  ASSERT_TRUE(receiver.factor(lower_of(B, {}), 1e-3));
  const std::vector<double> v = sender.values();
  ASSERT_FALSE(v.empty());
  EXPECT_FALSE(fresh.import_values(v.data(), v.size())) << "nothing analysed to take them into";
  EXPECT_FALSE(receiver.import_values(v.data(), v.size() - 1)) << "a different layout";
  ASSERT_TRUE(receiver.import_values(v.data(), v.size()));
  EXPECT_TRUE(receiver.ok());
  EXPECT_EQ(receiver.analyses(), 1);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
  Eigen::VectorXd want, got;
  sender.solve(b, want);
  receiver.solve(b, got);
  for (Eigen::Index i = 0; i < b.size(); ++i) ASSERT_EQ(got(i), want(i)) << "entry " << i;
  // Only L's entries travel: fewer values than the supernodes hold with their upper triangles.
  EXPECT_LE(v.size(), sender.factor_entries() + static_cast<std::size_t>(A.rows()) * 12);
}

TEST(SupernodalFactor, AfterAFailedFactorizationImportEitherSolvesLikeTheSenderOrRefuses) {
  // The receiver's own last factorization stopped at a pivot: the sender's values make its
  // factor complete (the same bits as the sender's), or import refuses and the receiver keeps
  // no usable factor; never a half-old factor.
  const Eigen::MatrixXd A = blocky(4, 10, 0.5, 3);
  Eigen::MatrixXd indefinite = A;
  indefinite(7, 7) = -50.0;
  SupernodalFactor sender, receiver;
  ASSERT_TRUE(sender.factor(lower_of(A, {}), 0.0));
  ASSERT_FALSE(receiver.factor(lower_of(indefinite, {}), 0.0));
  const std::vector<double> v = sender.values();
  if (!receiver.import_values(v.data(), v.size())) {
    EXPECT_FALSE(receiver.ok());
    return;
  }
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows());
  Eigen::VectorXd want, got;
  sender.solve(b, want);
  receiver.solve(b, got);
  EXPECT_EQ((got - want).norm(), 0.0);
}

// The AMD-ordered factor, whose input this class permutes itself (solvers/supernodal_factor.cpp),
// holds the bits of CHOLMOD's own factor of the same matrix (two transposes per factorization),
// and its solve gives CHOLMOD's solve's bits: at the analysis and at a later point's values.
TEST(SupernodalFactor, AmdFactorAndSolveEqualCholmodsOwnPermutedFactorToTheBit) {
  for (std::uint64_t seed : {11u, 12u}) {
    const SparseMatrix first = lower_of(blocky(6, 10, 0.5, seed), {{25, 3}, {41, 12}});
    const SparseMatrix later = lower_of(blocky(6, 10, 0.5, seed + 100), {{25, 3}, {41, 12}});
    ASSERT_TRUE(first.isCompressed());
    SupernodalFactor ours;
    cholmod_common c;
    cholmod_start(&c);
    c.print = 0;
    c.supernodal = CHOLMOD_SUPERNODAL;
    c.final_ll = 1;
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_AMD;
    c.postorder = 1;
    cholmod_sparse a0 = Eigen::viewAsCholmod(first.selfadjointView<Eigen::Lower>());
    cholmod_factor* L = cholmod_analyze(&a0, &c);
    ASSERT_NE(L, nullptr);
    ASSERT_NE(L->ordering, CHOLMOD_NATURAL);
    for (const SparseMatrix* m : {&first, &later}) {
      ASSERT_TRUE(ours.factor(*m, 1e-3));
      cholmod_sparse a = Eigen::viewAsCholmod(m->selfadjointView<Eigen::Lower>());
      double beta[2] = {1e-3, 0.0};
      ASSERT_TRUE(cholmod_factorize_p(&a, beta, nullptr, 0, L, &c));
      ASSERT_EQ(L->minor, L->n);
      // values(): each supernode's columns from the diagonal down, as CHOLMOD stores them.
      std::vector<double> want;
      const int* super = static_cast<const int*>(L->super);
      const int* pi = static_cast<const int*>(L->pi);
      const int* px = static_cast<const int*>(L->px);
      const double* x = static_cast<const double*>(L->x);
      for (std::size_t k = 0; k < L->nsuper; ++k) {
        const int nc = super[k + 1] - super[k], nr = pi[k + 1] - pi[k];
        for (int j = 0; j < nc; ++j)
          want.insert(want.end(), x + px[k] + j * nr + j, x + px[k] + (j + 1) * nr);
      }
      const std::vector<double> got = ours.values();
      ASSERT_EQ(got.size(), want.size());
      for (std::size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], want[i]) << "entry " << i;
      Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m->rows(), -1.0, 2.0), mine;
      ours.solve(b, mine);
      cholmod_dense* B = cholmod_allocate_dense(b.size(), 1, b.size(), CHOLMOD_REAL, &c);
      std::copy(b.data(), b.data() + b.size(), static_cast<double*>(B->x));
      cholmod_dense* X = cholmod_solve(CHOLMOD_A, L, B, &c);
      ASSERT_NE(X, nullptr);
      const double* xs = static_cast<const double*>(X->x);
      for (Eigen::Index i = 0; i < b.size(); ++i) ASSERT_EQ(mine(i), xs[i]) << "entry " << i;
      cholmod_free_dense(&X, &c);
      cholmod_free_dense(&B, &c);
    }
    EXPECT_EQ(ours.analyses(), 1);
    cholmod_free_factor(&L, &c);
    cholmod_finish(&c);
  }
}

}  // namespace
}  // namespace tessera
