#pragma once
// A fill-reducing elimination order (approximate minimum degree, Eigen::AMDOrdering) of a
// symmetric sparsity pattern. The substructuring factorizations (the refinement's interface
// solves and the certificate's interface test) order their blocks' interior unknowns by it
// (interface_last_order.hpp).

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace tessera {

/// order[k]: the unknown (of 0 .. n-1) that AMD eliminates k-th, for the pattern with an entry
/// at each (row, col) of `entries` (their values are not read; duplicates are allowed).
std::vector<Eigen::Index> amd_elimination_order(Eigen::Index n,
                                                const std::vector<Eigen::Triplet<double>>& entries);

}  // namespace tessera
