#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <tessera/problem/lifting.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/problem/translation_solve.hpp>

namespace tessera {

Eigen::MatrixXd round_rotations(const Eigen::MatrixXd& X, int d) {
  const Eigen::Index n = X.cols() / (d + 1);
  const Eigen::Index r = X.rows();
  Eigen::MatrixXd Y(r, d * n);
  for (Eigen::Index i = 0; i < n; ++i) Y.middleCols(d * i, d) = X.middleCols((d + 1) * i, d);
  // Top-d left singular vectors of Y from the small r x r Gram matrix.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Y * Y.transpose());
  Eigen::MatrixXd U = eig.eigenvectors().rightCols(d);  // ascending order: largest last
  Eigen::MatrixXd R = U.transpose() * Y;                // d x dn
  Eigen::Index negative = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    if (determinant_of(R.middleCols(d * i, d)) < 0) ++negative;
  if (2 * negative > n) R.row(d - 1) *= -1.0;  // reflect so most blocks are rotations
  for (Eigen::Index i = 0; i < n; ++i)
    project_to_rotation(R.middleCols(d * i, d), R.middleCols(d * i, d));
  return R;
}

std::vector<Pose> assemble_poses(const Eigen::MatrixXd& rotations,
                                 const Eigen::MatrixXd& translations) {
  const Eigen::Index d = translations.rows();
  const Eigen::Index n = translations.cols();
  std::vector<Pose> poses(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    poses[static_cast<std::size_t>(i)].R = rotations.middleCols(d * i, d);
    poses[static_cast<std::size_t>(i)].t = translations.col(i);
  }
  return poses;
}

std::vector<Pose> round_solution(const PoseGraph& graph, const Eigen::MatrixXd& X) {
  Eigen::MatrixXd R = round_rotations(X, graph.d);
  Eigen::MatrixXd t = solve_translations(graph, R);
  return assemble_poses(R, t);
}

}  // namespace tessera
