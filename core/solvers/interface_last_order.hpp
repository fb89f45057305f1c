#pragma once
// The substructuring factorizations' elimination order: the interior unknowns first, in a
// fill-reducing order (AMD on the pattern among them, elimination_order.hpp), the interface
// unknowns last, so the factor's trailing block is the interface's (its product with its
// transpose is the interface's Schur complement). One order for the refinement's interface
// solves (distributed/interface_solve.hpp: poses; distributed/translation_interface_solve.hpp:
// translations) and the certificate's interface test (certification/interface_schur.hpp:
// coordinates); each caller places its interface unknowns itself, in the order its Schur
// complement is shared in.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <vector>

#include "solvers/elimination_order.hpp"

namespace tessera {

/// `position`: one entry per unknown, the interface unknowns' positions (n_interior and up)
/// as the caller placed them and -1 for every interior unknown. `for_each_entry(add)` must
/// call add(row, col) for each entry of the symmetric pattern (unknowns 0 .. position.size()-1,
/// both triangles or one, duplicates allowed; entries touching an interface unknown are
/// skipped). On return every interior unknown has its position in 0 .. n_interior-1: the
/// approximate minimum degree order of the pattern among the interior unknowns.
template <class ForEachEntry>
void place_interior_first(std::vector<Eigen::Index>& position, ForEachEntry&& for_each_entry) {
  std::vector<Eigen::Index> interior_index(position.size(), -1), interior;
  for (std::size_t i = 0; i < position.size(); ++i)
    if (position[i] < 0) {
      interior_index[i] = static_cast<Eigen::Index>(interior.size());
      interior.push_back(static_cast<Eigen::Index>(i));
    }
  const auto n_interior = static_cast<Eigen::Index>(interior.size());
  if (n_interior == 0) return;
  std::vector<Eigen::Triplet<double>> pattern;
  for_each_entry([&](Eigen::Index row, Eigen::Index col) {
    const Eigen::Index a = interior_index[static_cast<std::size_t>(row)];
    const Eigen::Index c = interior_index[static_cast<std::size_t>(col)];
    if (a >= 0 && c >= 0) pattern.emplace_back(a, c, 1.0);
  });
  const std::vector<Eigen::Index> order = amd_elimination_order(n_interior, pattern);
  for (Eigen::Index k = 0; k < n_interior; ++k)
    position[static_cast<std::size_t>(
        interior[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])])] = k;
}

}  // namespace tessera
