#pragma once
// The sparse data matrix Q of the lifted PGO problem: for lifted poses X (see
// manifold/lifted_manifold.hpp), f(X) = tr(X Q X^T) equals the reference objective
//   sum_e kappa ||Y_j - Y_i R_ij||_F^2 + tau ||p_j - p_i - Y_i t_ij||^2   (the full sum).

#include <Eigen/SparseCore>
#include <cstddef>
#include <tessera/graph/measurement.hpp>
#include <vector>

namespace tessera {

using SparseMatrix = Eigen::SparseMatrix<double>;

/// Builds Q over `num_slots` poses. `slot_of_i[k]` / `slot_of_j[k]` give the slots (0-based,
/// < num_slots) of measurement k's endpoints. Q is (d+1)*num_slots square, symmetric PSD.
SparseMatrix build_data_matrix(const std::vector<const Measurement*>& measurements,
                               const std::vector<std::size_t>& slot_of_i,
                               const std::vector<std::size_t>& slot_of_j, int d,
                               std::size_t num_slots);

/// Q for a whole graph whose poses are slots 0..n-1.
SparseMatrix build_data_matrix(const std::vector<Measurement>& measurements, int d,
                               std::size_t num_poses);

/// The two parts of Q a block problem needs, with slots 0..num_owned-1 the block's own poses
/// and num_owned..num_slots-1 its neighbours: Q_BB (own rows and columns) and Q_NB
/// (neighbour rows, own columns). Exactly the corresponding blocks of build_data_matrix's Q
/// (same entries, explicit zeros included, same floating-point sums), built without the
/// neighbour columns.
struct DataMatrixBlocks {
  SparseMatrix own;        ///< Q_BB, (d+1)num_owned square.
  SparseMatrix neighbour;  ///< Q_NB, (d+1)(num_slots - num_owned) x (d+1)num_owned.
};
DataMatrixBlocks build_data_matrix_blocks(const std::vector<const Measurement*>& measurements,
                                          const std::vector<std::size_t>& slot_of_i,
                                          const std::vector<std::size_t>& slot_of_j, int d,
                                          std::size_t num_slots, std::size_t num_owned);

}  // namespace tessera
