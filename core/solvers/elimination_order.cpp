#include "solvers/elimination_order.hpp"

#include <Eigen/OrderingMethods>
#include <tessera/problem/data_matrix.hpp>

namespace tessera {

std::vector<Eigen::Index> amd_elimination_order(
    Eigen::Index n, const std::vector<Eigen::Triplet<double>>& entries) {
  SparseMatrix pattern(n, n);
  pattern.setFromTriplets(entries.begin(), entries.end());
  Eigen::AMDOrdering<int> amd;
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
  amd(pattern, perm);
  // perm.indices()(k): the unknown eliminated k-th.
  std::vector<Eigen::Index> order(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k) order[static_cast<std::size_t>(k)] = perm.indices()(k);
  return order;
}

}  // namespace tessera
