#include "certification/row_space_ritz.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <vector>

namespace tessera {

PencilPair smallest_pencil_pair(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::Index k = b.rows();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eb(b);
  const double top = eb.eigenvalues().maxCoeff();
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < k; ++i)
    if (eb.eigenvalues()(i) > 1e-10 * top) keep.push_back(i);
  Eigen::MatrixXd Z(k, static_cast<Eigen::Index>(keep.size()));
  for (std::size_t c = 0; c < keep.size(); ++c)
    Z.col(static_cast<Eigen::Index>(c)) =
        eb.eigenvectors().col(keep[c]) / std::sqrt(eb.eigenvalues()(keep[c]));
  Eigen::MatrixXd C = Z.transpose() * a * Z;
  C = (0.5 * (C + C.transpose())).eval();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> ec(C);
  return {Z * ec.eigenvectors().col(0), ec.eigenvalues()(0)};
}

RowSpaceRitz row_space_ritz(const Eigen::MatrixXd& yy, const Eigen::MatrixXd& ysy,
                            const Eigen::MatrixXd& ss) {
  const PencilPair pair = smallest_pencil_pair(ysy, yy);
  RowSpaceRitz out;
  out.coefficients = pair.vector;
  out.theta = pair.value;
  // ||x S - theta x||^2 = c^T (Y S)(Y S)^T c - theta^2 for c^T Y Y^T c = 1.
  out.residual =
      std::sqrt(std::max(0.0, out.coefficients.dot(ss * out.coefficients) - out.theta * out.theta));
  return out;
}

}  // namespace tessera
