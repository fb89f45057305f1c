#pragma once
// Moving between poses in SE(d) and lifted poses in (St(r,d) x R^r)^n, and projections
// of matrices onto SO(d).

#include <Eigen/Core>
#include <cstddef>
#include <tessera/graph/pose.hpp>
#include <vector>

namespace tessera {

/// X = [I_d; 0] [R_1 t_1 | ... | R_n t_n]: the poses embedded at rank r >= d.
Eigen::MatrixXd lift_poses(const std::vector<Pose>& poses, int r);

/// The columns of the poses `ids` of the lifted iterate X (r x (d+1)n), in the order of `ids`:
/// an agent's block of X (its own poses) or its copies of its neighbours' poses, r x (d+1)|ids|.
/// Throws std::out_of_range if an id is not a pose of X.
Eigen::MatrixXd gather_pose_columns(const Eigen::MatrixXd& X, const std::vector<std::size_t>& ids,
                                    int d);

/// The inverse of gather_pose_columns: writes the block Y (r x (d+1)|ids|, the poses `ids` in
/// that order) into those poses' columns of X (r x (d+1)n); X's other columns stay. Throws
/// std::invalid_argument if Y's size does not match X's rows and `ids`, std::out_of_range if an
/// id is not a pose of X.
void scatter_pose_columns(const Eigen::MatrixXd& Y, const std::vector<std::size_t>& ids, int d,
                          Eigen::MatrixXd& X);

/// Nearest rotation (det +1) to a square matrix.
Eigen::MatrixXd project_to_rotation(const Eigen::MatrixXd& A);
/// The same written into `out` (A's size; it may be A itself), without heap allocations for
/// 2 x 2 and 3 x 3 (the same bits as the returning form). Throws std::invalid_argument if A is
/// not square or `out` is not its size.
void project_to_rotation(const Eigen::Ref<const Eigen::MatrixXd>& A,
                         Eigen::Ref<Eigen::MatrixXd> out);

/// Determinant of a square matrix: 2 x 2 and 3 x 3 by their closed forms, without the heap (the
/// dynamic-size determinant factors an LU copy); the last bits may differ from that one's, so
/// its sign is what callers compare (the rounding's side of each block: rotation or reflection).
double determinant_of(const Eigen::Ref<const Eigen::MatrixXd>& A);

/// Adds `extra` zero rows (the staircase's rank increase keeps the cost unchanged).
Eigen::MatrixXd pad_rank(const Eigen::MatrixXd& X, int extra);

}  // namespace tessera
