#pragma once
// Moving between poses in SE(d) and lifted poses in (St(r,d) x R^r)^n, and projections
// of matrices onto SO(d).

#include <Eigen/Core>
#include <tessera/graph/pose.hpp>
#include <vector>

namespace tessera {

/// X = [I_d; 0] [R_1 t_1 | ... | R_n t_n]: the poses embedded at rank r >= d.
Eigen::MatrixXd lift_poses(const std::vector<Pose>& poses, int r);

/// Nearest rotation (det +1) to a square matrix.
Eigen::MatrixXd project_to_rotation(const Eigen::MatrixXd& A);

/// Adds `extra` zero rows (the staircase's rank increase keeps the cost unchanged).
Eigen::MatrixXd pad_rank(const Eigen::MatrixXd& X, int extra);

}  // namespace tessera
