#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <tessera/problem/translation_solve.hpp>

#include "solvers/cholmod_checked.hpp"

namespace tessera {

Eigen::MatrixXd solve_translations(const PoseGraph& graph, const Eigen::MatrixXd& rotations,
                                   std::size_t anchor) {
  const int d = graph.d;
  const std::size_t n = graph.num_poses;
  // Unknowns: every pose but the anchor, one Laplacian shared by the d coordinates.
  auto var = [&](std::size_t id) -> long {
    if (id == anchor) return -1;
    return static_cast<long>(id < anchor ? id : id - 1);
  };
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(graph.measurements.size() * 4);
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n - 1), d);
  for (const auto& m : graph.measurements) {
    const long vi = var(m.i), vj = var(m.j);
    Eigen::VectorXd c = rotations.middleCols(static_cast<Eigen::Index>(d * m.i), d) * m.t;
    if (vi >= 0) {
      trip.emplace_back(vi, vi, m.tau);
      b.row(vi) -= m.tau * c.transpose();
    }
    if (vj >= 0) {
      trip.emplace_back(vj, vj, m.tau);
      b.row(vj) += m.tau * c.transpose();
    }
    if (vi >= 0 && vj >= 0) {
      trip.emplace_back(vi, vj, -m.tau);
      trip.emplace_back(vj, vi, -m.tau);
    }
  }
  Eigen::SparseMatrix<double> L(static_cast<Eigen::Index>(n - 1), static_cast<Eigen::Index>(n - 1));
  L.setFromTriplets(trip.begin(), trip.end());
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(d, static_cast<Eigen::Index>(n));
  if (n == 1) return t;
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> chol;
  chol.setMode(Eigen::CholmodAuto);  // CHOLMOD chooses simplicial or supernodal
  cholmod_compute_checked(chol, L, "solve_translations");
  if (chol.info() != Eigen::Success)
    throw std::runtime_error(
        "solve_translations: Laplacian factorization failed (disconnected graph?)");
  Eigen::MatrixXd sol = chol.solve(b);
  for (std::size_t id = 0; id < n; ++id) {
    long v = var(id);
    if (v >= 0) t.col(static_cast<Eigen::Index>(id)) = sol.row(v).transpose();
  }
  return t;
}

}  // namespace tessera
