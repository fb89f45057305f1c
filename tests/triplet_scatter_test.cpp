// TripletScatter: a matrix assembled again at the same positions is setFromTriplets' matrix.

#include "solvers/triplet_scatter.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace tessera {
namespace {

TEST(TripletScatter, RefilledMatrixIsSetFromTripletsMatrixToTheBitExplicitZerosIncluded) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> pick(0, 39);
  std::normal_distribution<double> g;
  // Distinct positions in a scrambled order (the callers' order is not column order).
  std::vector<int> rows, cols;
  std::vector<std::vector<bool>> used(40, std::vector<bool>(40, false));
  while (rows.size() < 300) {
    const int r = pick(rng), c = pick(rng);
    if (used[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)]) continue;
    used[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)] = true;
    rows.push_back(r);
    cols.push_back(c);
  }
  TripletScatter scatter;
  ASSERT_TRUE(scatter.build(40, rows, cols));
  EXPECT_TRUE(scatter.matches(40, rows, cols));
  for (int point = 0; point < 3; ++point) {
    std::vector<double> v(rows.size());
    std::vector<Eigen::Triplet<double>> t;
    for (std::size_t k = 0; k < v.size(); ++k) {
      v[k] = k % 17 == 0 ? 0.0 : g(rng);  // explicit zeros stay entries
      t.emplace_back(rows[k], cols[k], v[k]);
    }
    SparseMatrix want(40, 40);
    want.setFromTriplets(t.begin(), t.end());
    scatter.fill(v);
    const SparseMatrix& got = scatter.matrix();
    ASSERT_EQ(got.nonZeros(), want.nonZeros());
    for (Eigen::Index j = 0; j <= 40; ++j)
      ASSERT_EQ(got.outerIndexPtr()[j], want.outerIndexPtr()[j]);
    for (Eigen::Index i = 0; i < want.nonZeros(); ++i) {
      ASSERT_EQ(got.innerIndexPtr()[i], want.innerIndexPtr()[i]);
      ASSERT_EQ(got.valuePtr()[i], want.valuePtr()[i]);
    }
  }
}

TEST(TripletScatter, RepeatedOrOutOfRangePositionsAreRefused) {
  TripletScatter scatter;
  EXPECT_FALSE(scatter.build(3, {0, 1, 0}, {0, 1, 0})) << "a position twice would be summed";
  EXPECT_FALSE(scatter.matches(3, {0, 1, 0}, {0, 1, 0}));
  EXPECT_FALSE(scatter.build(3, {0, 3}, {0, 0}));
  EXPECT_FALSE(scatter.build(3, {0, 1}, {0}));
  ASSERT_TRUE(scatter.build(3, {2, 0}, {0, 0}));
  EXPECT_FALSE(scatter.matches(3, {0, 2}, {0, 0})) << "the same positions in another order";
  EXPECT_THROW(scatter.fill(std::vector<double>{1.0}), std::logic_error);
}

}  // namespace
// assign() takes the entries as triplets: the same matrix as setFromTriplets at every point,
// laid out again only when the positions change, and refused (nothing held) on a repeat.
TEST(TripletScatter, AssignedTripletsGiveSetFromTripletsMatrixAndRelayoutOnNewPositions) {
  auto same = [](const SparseMatrix& got, const std::vector<Eigen::Triplet<double>>& t) {
    SparseMatrix want(4, 4);
    want.setFromTriplets(t.begin(), t.end());
    if (got.nonZeros() != want.nonZeros()) return false;
    for (Eigen::Index i = 0; i < want.nonZeros(); ++i)
      if (got.innerIndexPtr()[i] != want.innerIndexPtr()[i] ||
          got.valuePtr()[i] != want.valuePtr()[i])
        return false;
    return true;
  };
  TripletScatter scatter;
  std::vector<Eigen::Triplet<double>> t{{3, 0, 1.5}, {0, 0, 2.0}, {2, 1, 0.0}};
  ASSERT_TRUE(scatter.assign(4, t));
  EXPECT_TRUE(same(scatter.matrix(), t));
  t = {{3, 0, -4.0}, {0, 0, 7.0}, {2, 1, 0.25}};  // same positions, new values
  ASSERT_TRUE(scatter.assign(4, t));
  EXPECT_TRUE(same(scatter.matrix(), t));
  t = {{1, 1, 3.0}, {3, 0, 1.0}};  // new positions: laid out again
  ASSERT_TRUE(scatter.assign(4, t));
  EXPECT_TRUE(same(scatter.matrix(), t));
  EXPECT_FALSE(scatter.assign(4, {{1, 1, 1.0}, {1, 1, 2.0}}));
  EXPECT_THROW(scatter.fill(std::vector<double>{1.0, 2.0}), std::logic_error);
}

}  // namespace tessera
