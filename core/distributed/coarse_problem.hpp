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

/// Throws runtime_error ("coarse correction: ... term vectors for ... blocks") unless there is
/// one term vector per block.
void check_coarse_term_vectors(std::size_t vectors, int blocks);

/// Throws runtime_error ("malformed message: coarse terms of agent ...: ... values, expected
/// ...") when agent's terms do not hold `expected` values.
void check_coarse_term_size(const std::vector<double>& terms, std::size_t expected, int agent);

/// The rows of the lifted space an agent's coarse terms use, read from their first entry (a
/// bit mask over the r rows), with the translation row r appended. Throws runtime_error
/// ("malformed message: coarse terms of agent ...") on an empty vector or a mask that is not
/// an integer in [0, 2^r).
std::vector<int> coarse_term_rows(const std::vector<double>& terms, int r, int agent);

/// The encoding's counterpart of coarse_term_rows: the rows of X and of the neighbour copies Xn
/// that some pose uses (others are exact zeros and are not sent), with row r = X.rows()
/// appended; `mask` gets their bit mask, the terms' first entry.
std::vector<int> coarse_rows_in_use(const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn,
                                    double& mask);

/// Appends M's entries at (rows[i], rows[j]) to `out` in the order add_packed_block reads them.
void append_packed_block(const Eigen::MatrixXd& M, const std::vector<int>& rows, bool symmetric,
                         std::vector<double>& out);

/// Adds the values t[at], t[at+1], ... to M at (rows[i], rows[j]): the upper triangle column by
/// column, mirrored (`symmetric`), or the whole rows x rows block column by column. Leaves `at`
/// after the last value read.
void add_packed_block(const std::vector<double>& t, std::size_t& at, const std::vector<int>& rows,
                      bool symmetric, Eigen::MatrixXd& M);

/// A cut edge i -> j lifted to the (r+1) x (d+1) matrices whose difference Z_j A - Z_i B is its
/// residual under rigid motions Z: the target's A = [sk [Y_j; 0], st [p_j; 1]] and the
/// source's B = [sk [Y_i R; 0], st [p_i + Y_i t; 1]], sk = sqrt(kappa), st = sqrt(tau). P is
/// the pose's r x (d+1) block; M's other entries are left as they are (zero).
inline void lift_target(Eigen::MatrixXd& M, const Eigen::Ref<const Eigen::MatrixXd>& P, int d,
                        double sk, double st) {
  const Eigen::Index r = P.rows();
  M.topLeftCorner(r, d) = sk * P.leftCols(d);
  M.col(d).head(r) = st * P.col(d);
  M(r, d) = st;
}

inline void lift_source(Eigen::MatrixXd& M, const Eigen::Ref<const Eigen::MatrixXd>& P,
                        const Eigen::MatrixXd& R, const Eigen::VectorXd& t, int d, double sk,
                        double st) {
  const Eigen::Index r = P.rows();
  M.topLeftCorner(r, d) = sk * (P.leftCols(d) * R);
  M.col(d).head(r) = st * (P.col(d) + P.leftCols(d) * t);
  M(r, d) = st;
}

/// Levenberg-Marquardt from the identity motions in the tangent space of the rigid motions
/// (Cayley retraction), on the rows of the lifted space that some pose uses. Deterministic:
/// the same Q gives bit-identical motions. motions[a] is r x (r+1).
CoarseResult solve_coarse_matrix(CoarseMatrix Q, int r, const CoarseOptions& options);

}  // namespace tessera
