#include <Eigen/LU>
#include <Eigen/SVD>
#include <tessera/problem/lifting.hpp>

namespace tessera {

Eigen::MatrixXd lift_poses(const std::vector<Pose>& poses, int r) {
  const int d = poses.empty() ? 0 : poses.front().dim();
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(r, (d + 1) * static_cast<Eigen::Index>(poses.size()));
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Index c = (d + 1) * static_cast<Eigen::Index>(i);
    X.block(0, c, d, d) = poses[i].R;
    X.block(0, c + d, d, 1) = poses[i].t;
  }
  return X;
}

Eigen::MatrixXd project_to_rotation(const Eigen::MatrixXd& A) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::MatrixXd U = svd.matrixU();
  const Eigen::MatrixXd& V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0) U.col(U.cols() - 1) *= -1.0;
  return U * V.transpose();
}

Eigen::MatrixXd pad_rank(const Eigen::MatrixXd& X, int extra) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(X.rows() + extra, X.cols());
  out.topRows(X.rows()) = X;
  return out;
}

}  // namespace tessera
