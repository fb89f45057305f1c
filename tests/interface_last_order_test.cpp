// place_interior_first (solvers/interface_last_order.hpp): the substructuring factorizations'
// order, interior unknowns first in AMD order, the interface where the caller put it.

#include "solvers/interface_last_order.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "solvers/elimination_order.hpp"

namespace tessera {
namespace {

using Pattern = std::vector<std::pair<Eigen::Index, Eigen::Index>>;

// A star among the interior unknowns {0, 2, 3, 5, 6, 7} (hub 3) and two interface unknowns
// (1, 4) coupled to every interior one, both triangles.
Pattern star_with_interface() {
  Pattern p;
  for (Eigen::Index leaf : {0, 2, 5, 6, 7}) {
    p.emplace_back(3, leaf);
    p.emplace_back(leaf, 3);
  }
  for (Eigen::Index i : {0, 2, 3, 5, 6, 7})
    for (Eigen::Index g : {1, 4}) {
      p.emplace_back(i, g);
      p.emplace_back(g, i);
    }
  for (Eigen::Index i = 0; i < 8; ++i) p.emplace_back(i, i);
  return p;
}

std::vector<Eigen::Index> placed(std::vector<Eigen::Index> position, const Pattern& pattern) {
  place_interior_first(position, [&](const auto& add) {
    for (const auto& [r, c] : pattern) add(r, c);
  });
  return position;
}

TEST(InterfaceLastOrder, TheInterfaceKeepsItsPositionsAndTheInteriorFillsTheFirstOnes) {
  // Interface unknowns 1 and 4 at the end, in the caller's order (4 before 1).
  const std::vector<Eigen::Index> pos =
      placed({-1, 7, -1, -1, 6, -1, -1, -1}, star_with_interface());
  EXPECT_EQ(pos[1], 7);
  EXPECT_EQ(pos[4], 6);
  std::vector<Eigen::Index> interior;
  for (Eigen::Index i : {0, 2, 3, 5, 6, 7}) interior.push_back(pos[static_cast<std::size_t>(i)]);
  std::sort(interior.begin(), interior.end());
  EXPECT_EQ(interior, (std::vector<Eigen::Index>{0, 1, 2, 3, 4, 5}));
}

TEST(InterfaceLastOrder, TheInteriorIsInTheAmdOrderOfItsOwnPattern) {
  const std::vector<Eigen::Index> pos =
      placed({-1, 7, -1, -1, 6, -1, -1, -1}, star_with_interface());
  // The star alone, in interior numbering (0, 2, 3, 5, 6, 7 -> 0 .. 5; the hub is 2): the
  // couplings to the interface play no part.
  std::vector<Eigen::Triplet<double>> star;
  for (Eigen::Index leaf : {0, 1, 3, 4, 5}) {
    star.emplace_back(2, leaf, 1.0);
    star.emplace_back(leaf, 2, 1.0);
  }
  for (Eigen::Index i = 0; i < 6; ++i) star.emplace_back(i, i, 1.0);
  const std::vector<Eigen::Index> order = amd_elimination_order(6, star);
  const std::vector<Eigen::Index> unknown = {0, 2, 3, 5, 6, 7};
  for (std::size_t k = 0; k < order.size(); ++k)
    EXPECT_EQ(pos[static_cast<std::size_t>(unknown[static_cast<std::size_t>(order[k])])],
              static_cast<Eigen::Index>(k));
  // Minimum degree eliminates leaves before the hub: no fill.
  EXPECT_GE(pos[3], 4);
}

TEST(InterfaceLastOrder, AllInterfaceIsLeftAsPlacedWithoutReadingThePattern) {
  std::vector<Eigen::Index> pos = {1, 0, 2};
  bool read = false;
  place_interior_first(pos, [&](const auto&) { read = true; });
  EXPECT_EQ(pos, (std::vector<Eigen::Index>{1, 0, 2}));
  EXPECT_FALSE(read);
}

}  // namespace
}  // namespace tessera
