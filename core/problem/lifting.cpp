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

namespace {

// out = U V^T entry by entry, each sum over c in increasing order: the arithmetic of the
// dynamic-size product (Eigen's fixed-size product of 2 x 2 and 3 x 3 matrices is vectorized in
// another order and would move the last bit).
template <int D>
void times_transpose(const Eigen::Matrix<double, D, D>& U, const Eigen::Matrix<double, D, D>& V,
                     Eigen::Matrix<double, D, D>& out) {
  for (int j = 0; j < D; ++j)
    for (int i = 0; i < D; ++i) {
      double acc = U(i, 0) * V(j, 0);
      for (int c = 1; c < D; ++c) acc += U(i, c) * V(j, c);
      out(i, j) = acc;
    }
}

// project_to_rotation for d = 2, 3 without the heap: a fixed-size JacobiSVD computes the same U
// and V as the dynamic-size one (the same sweeps; the dynamic one's QR preconditioner is skipped
// for square matrices), and the products are formed as the dynamic ones are, so the result is the
// same to the bit, in a quarter to a half of the instructions (the dynamic SVD's allocations were
// most of its cost on 2 x 2 blocks). The determinant's sign decides alike (it is +-1).
template <int D>
void nearest_rotation(const Eigen::Ref<const Eigen::MatrixXd>& A, Eigen::Ref<Eigen::MatrixXd> out) {
  using Small = Eigen::Matrix<double, D, D>;
  const Small a = A;
  Eigen::JacobiSVD<Small> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Small U = svd.matrixU();
  const Small& V = svd.matrixV();
  Small R;
  times_transpose<D>(U, V, R);
  if (R.determinant() < 0) {
    U.col(D - 1) *= -1.0;
    times_transpose<D>(U, V, R);
  }
  out = R;
}

}  // namespace

void project_to_rotation(const Eigen::Ref<const Eigen::MatrixXd>& A,
                         Eigen::Ref<Eigen::MatrixXd> out) {
  if (A.rows() != A.cols() || out.rows() != A.rows() || out.cols() != A.cols())
    throw std::invalid_argument("project_to_rotation: " + std::to_string(A.rows()) + " x " +
                                std::to_string(A.cols()) + " into " + std::to_string(out.rows()) +
                                " x " + std::to_string(out.cols()));
  if (A.rows() == 2) return nearest_rotation<2>(A, out);
  if (A.rows() == 3) return nearest_rotation<3>(A, out);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::MatrixXd U = svd.matrixU();
  const Eigen::MatrixXd& V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0) U.col(U.cols() - 1) *= -1.0;
  out = U * V.transpose();
}

Eigen::MatrixXd project_to_rotation(const Eigen::MatrixXd& A) {
  Eigen::MatrixXd out(A.rows(), A.cols());
  project_to_rotation(A, out);
  return out;
}

double determinant_of(const Eigen::Ref<const Eigen::MatrixXd>& A) {
  if (A.rows() == 2 && A.cols() == 2) return Eigen::Matrix2d(A).determinant();
  if (A.rows() == 3 && A.cols() == 3) return Eigen::Matrix3d(A).determinant();
  return Eigen::MatrixXd(A).determinant();
}

Eigen::MatrixXd pad_rank(const Eigen::MatrixXd& X, int extra) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(X.rows() + extra, X.cols());
  out.topRows(X.rows()) = X;
  return out;
}

}  // namespace tessera
