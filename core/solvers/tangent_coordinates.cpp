#include "solvers/tangent_coordinates.hpp"

namespace tessera {

std::vector<std::pair<int, int>> skew_pairs(int d) {
  std::vector<std::pair<int, int>> out;
  for (int a = 0; a < d; ++a)
    for (int b = a + 1; b < d; ++b) out.emplace_back(a, b);
  return out;
}

Eigen::MatrixXd pose_basis(const Eigen::Ref<const Eigen::MatrixXd>& Y,
                           const std::vector<std::pair<int, int>>& pairs) {
  const Eigen::Index d = Y.rows();
  const Eigen::Index nr = static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(d * (d + 1), nr + d);
  for (Eigen::Index k = 0; k < nr; ++k) {
    const auto [a, b] = pairs[static_cast<std::size_t>(k)];
    // Y E_ab: column a is Y e_b, column b is -Y e_a.
    G.block(a * d, k, d, 1) = Y.col(b);
    G.block(b * d, k, d, 1) = -Y.col(a);
  }
  G.block(d * d, nr, d, d) = Y;
  return G;
}

void tangent_block(const Eigen::Ref<const Eigen::MatrixXd>& Qij, const Eigen::MatrixXd& Gi,
                   const Eigen::MatrixXd& Gj, int d, Eigen::MatrixXd& T, Eigen::MatrixXd& B) {
  const int w = d + 1;
  for (int t = 0; t < w; ++t) {
    auto row = T.middleRows(t * d, d);
    row.setZero();
    for (int u = 0; u < w; ++u)
      if (Qij(t, u) != 0.0) row.noalias() += Qij(t, u) * Gj.middleRows(u * d, d);
  }
  B.noalias() = 2.0 * Gi.transpose() * T;
}

}  // namespace tessera
