#include <Eigen/Eigenvalues>
#include <stdexcept>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/online/lifted_rank.hpp>

namespace tessera {

Eigen::MatrixXd project_to_rank(const Eigen::MatrixXd& X, int d, int r) {
  if (d < 2 || r < d || r > X.rows() || X.cols() % (d + 1) != 0)
    throw std::invalid_argument("project_to_rank: needs 2 <= d <= r <= X.rows() and lifted poses");
  if (r == X.rows()) return X;
  // A rank-d optimum's translations lie in its rotations' span up to one common offset: the
  // offset is dropped, and the centred translations enter the principal directions beside the
  // rotations.
  const Eigen::Index w = d + 1, n = X.cols() / w;
  Eigen::MatrixXd centred = X;
  if (n > 0) {
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(X.rows());
    for (Eigen::Index k = 0; k < n; ++k) mean += X.col(w * k + d);
    mean /= static_cast<double>(n);
    for (Eigen::Index k = 0; k < n; ++k) centred.col(w * k + d) -= mean;
  }
  const Eigen::MatrixXd G = centred * centred.transpose();  // sum_i Y_i Y_i^T + p_i p_i^T
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(G);
  const Eigen::MatrixXd U = eig.eigenvectors().rightCols(r);  // top r directions
  Eigen::MatrixXd out = U.transpose() * centred;
  for (Eigen::Index k = 0; k < n; ++k) {
    auto Yk = out.middleCols(w * k, d);
    Yk = polar_factor(Eigen::MatrixXd(Yk));
  }
  return out;
}

}  // namespace tessera
