#pragma once
// The exact distributed test of S + D > 0 by substructuring (non-overlapping domain
// decomposition). A separator C covers the cut (every cut measurement has an endpoint in C);
// block b's other poses I_b are coupled to nothing outside the block but separator poses. Then
//   S + D > 0  <=>  every block's (S + D)_{I_b I_b} > 0  and  Sigma > 0,
//   Sigma = (S + D)_CC - sum_b S_{C I_b} (S + D)_{I_b I_b}^-1 S_{I_b C}
// (D: the proof's diagonal shift, positive on the rotation coordinates and on global pose 0's
// translation, zero on the other translations; dual_bound.hpp: what S + D > 0 proves)
// (the Schur complement lemma). Block b's term lives on its own separator poses and the foreign
// ones next to its eliminated poses (Gamma_b); each agent computes it from one supernodal
// factorization (CHOLMOD) of its block and those foreign poses, ordered last, as Schur_b =
// L_GG L_GG^T, L_GG the factor's trailing block. C = every pose with a cut measurement is the
// classic interface (local_interface_schur); C = one endpoint per cut measurement halves Sigma
// (local_separator_schur). A proof like the centralized certificate's factorization, not an
// iteration that may stop early.

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/data_matrix.hpp>
#include <vector>

namespace tessera {

/// One block's share of Sigma.
struct InterfaceSchurBlock {
  bool positive_definite = false;  ///< S_BB + D factored (else S + D is not PD).
  /// Gamma_b, global ids: the kept own poses (in the caller's order), then the foreign
  /// separator poses coupled to an eliminated own pose (ascending).
  std::vector<std::size_t> poses;
  /// Schur_b on poses' coordinates (pose-major): Gamma_b's own entries of S + D minus
  /// S_{Gamma I} (S + D)_{II}^-1 S_{I Gamma}; a foreign pose's own entries are its owner's.
  Eigen::MatrixXd schur;
  /// Coupling entries to other blocks' interface poses, global coordinates (pose (d+1) + c),
  /// each cut pose pair sent once: by the block owning the smaller pose id.
  std::vector<Eigen::Index> rows, cols;
  std::vector<double> values;
};

/// Block b's share. `lambda` is Lambda_B on the block's coordinates (owned order), `shift` the
/// diagonal D added to S there (dual_bound.hpp: proof_shift_diagonal), `interface_poses` the
/// block's interface (global ids, ascending, all owned).
InterfaceSchurBlock local_interface_schur(const BlockProblem& problem, const SparseMatrix& lambda,
                                          const Eigen::VectorXd& shift,
                                          const std::vector<std::size_t>& interface_poses);

/// The same share when only a separator C is kept: `kept` are the block's poses in C (owned,
/// any order), `in_separator(id)` says whether a global pose is in C. C must cover the cut
/// (every cut measurement has an endpoint in C); the block's other poses, cut ones included,
/// are eliminated, and their coupling to the neighbours' separator poses (the measurements'
/// entries of Q) enters its Schur complement over the kept and those foreign poses. With C
/// one endpoint of each cut measurement, Sigma has about half the coordinates of the
/// interface's. local_interface_schur is the case C = every interface pose.
InterfaceSchurBlock local_separator_schur(const BlockProblem& problem, const SparseMatrix& lambda,
                                          const Eigen::VectorXd& shift,
                                          const std::vector<std::size_t>& kept,
                                          const std::function<bool(std::size_t)>& in_separator);

/// As a message's values and back (the layout of the values is private to these two).
std::vector<double> encode_interface_schur(const InterfaceSchurBlock& block);
/// Throws std::runtime_error when `values` are not an encoded block.
InterfaceSchurBlock decode_interface_schur(const std::vector<double>& values);

/// Every block's share (in block order) gives the verdict S + D > 0 (Sigma: the shares'
/// Schur complements summed where their poses meet, plus the coupling entries). d: the graph's
/// dimension (a pose has d + 1 coordinates).
bool interface_positive_definite(const std::vector<InterfaceSchurBlock>& blocks, int d);

}  // namespace tessera
