#include <Eigen/LU>
#include <Eigen/SVD>
#include <stdexcept>
#include <string>
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

namespace {

// Column offset of pose `id` in X, checked: a wrong id would otherwise read or write out of
// bounds silently in Release builds.
Eigen::Index pose_column(const Eigen::MatrixXd& X, std::size_t id, Eigen::Index w) {
  const Eigen::Index c = w * static_cast<Eigen::Index>(id);
  if (c + w > X.cols())
    throw std::out_of_range("lifted iterate: pose " + std::to_string(id) + " of " +
                            std::to_string(X.cols() / w) + " poses");
  return c;
}

}  // namespace

Eigen::MatrixXd gather_pose_columns(const Eigen::MatrixXd& X, const std::vector<std::size_t>& ids,
                                    int d) {
  const Eigen::Index w = d + 1;
  Eigen::MatrixXd Y(X.rows(), w * static_cast<Eigen::Index>(ids.size()));
  for (std::size_t s = 0; s < ids.size(); ++s)
    Y.middleCols(w * static_cast<Eigen::Index>(s), w) = X.middleCols(pose_column(X, ids[s], w), w);
  return Y;
}

void scatter_pose_columns(const Eigen::MatrixXd& Y, const std::vector<std::size_t>& ids, int d,
                          Eigen::MatrixXd& X) {
  const Eigen::Index w = d + 1;
  if (Y.rows() != X.rows() || Y.cols() != w * static_cast<Eigen::Index>(ids.size()))
    throw std::invalid_argument("lifted block: " + std::to_string(Y.rows()) + " x " +
                                std::to_string(Y.cols()) + " for " + std::to_string(ids.size()) +
                                " poses of an iterate with " + std::to_string(X.rows()) + " rows");
  for (std::size_t s = 0; s < ids.size(); ++s)
    X.middleCols(pose_column(X, ids[s], w), w) = Y.middleCols(w * static_cast<Eigen::Index>(s), w);
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
