#pragma once
// Internal: the coarse problem min tr(Z Q_c Z^T) over rigid motions Z_a = [G_a c_a], the part
// shared by the block coarse space (coarse_correction.cpp) and the smoothed one
// (coarse_space.cpp): they differ in what a motion moves and in how Q_c is summed.

#include <Eigen/Core>
#include <map>
#include <string>
#include <tessera/distributed/coarse_correction.hpp>
#include <vector>

namespace tessera {

/// Q_c in (r+1) x (r+1) blocks: diag[a] = Q_aa, off[a][b] = Q_ab for every coupled b (both
/// directions kept, off[b][a] = off[a][b]^T).
struct CoarseMatrix {
  std::vector<Eigen::MatrixXd> diag;
  std::vector<std::map<int, Eigen::MatrixXd>> off;
};

/// The rows of the lifted space an agent's coarse terms use, read from their first entry (a
/// bit mask over the r rows), with the translation row r appended. Throws runtime_error
/// ("malformed message: coarse terms of agent ...") on an empty vector or a mask that is not
/// an integer in [0, 2^r).
std::vector<int> coarse_term_rows(const std::vector<double>& terms, int r, int agent);

/// Levenberg-Marquardt from the identity motions in the tangent space of the rigid motions
/// (Cayley retraction), on the rows of the lifted space that some pose uses. Deterministic:
/// the same Q gives bit-identical motions. motions[a] is r x (r+1).
CoarseResult solve_coarse_matrix(CoarseMatrix Q, int r, const CoarseOptions& options);

}  // namespace tessera
