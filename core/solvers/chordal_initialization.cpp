#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <tessera/problem/lifting.hpp>
#include <tessera/problem/rounding.hpp>
#include <tessera/problem/translation_solve.hpp>
#include <tessera/solvers/chordal_initialization.hpp>

#include "solvers/cholmod_checked.hpp"

namespace tessera {

Eigen::MatrixXd chordal_rotations(const PoseGraph& graph, bool simplicial) {
  using Index = Eigen::Index;
  const Index d = graph.d;
  const Index n = static_cast<Index>(graph.num_poses);
  // Each row a of the rotations decouples: with z_i = (row a of R_i)^T, minimise
  // sum kappa ||z_j - R_ij^T z_i||^2. One normal matrix H serves all d rows.
  // The triplets and H are freed before the factorization, the solve's memory peak (an agent
  // of a large run initialises its whole block with this).
  Eigen::SparseMatrix<double> H(d * n, d * n);
  {
    std::vector<Eigen::Triplet<double>> trip;
    trip.reserve(graph.measurements.size() * static_cast<std::size_t>(4 * d * d));
    for (const auto& m : graph.measurements) {
      const Index bi = d * static_cast<Index>(m.i), bj = d * static_cast<Index>(m.j);
      // B = [-R^T at i, I at j]; H += kappa B^T B.
      for (Index a = 0; a < d; ++a) {
        trip.emplace_back(bj + a, bj + a, m.kappa);
        trip.emplace_back(bi + a, bi + a, m.kappa);  // R R^T = I
        for (Index c = 0; c < d; ++c) {
          // (B^T B)_{i,j} = (-R^T)^T I = -R ; entry (bi+a, bj+c) = -R(a,c)
          trip.emplace_back(bi + a, bj + c, -m.kappa * m.R(a, c));
          trip.emplace_back(bj + c, bi + a, -m.kappa * m.R(a, c));
        }
      }
    }
    H.setFromTriplets(trip.begin(), trip.end());
  }
  // Anchor pose 0: z_0 = e_a for row a. Reduced system H_rr Z = -H_r0 I.
  const Index m = d * (n - 1);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(d, d * n);
  R.leftCols(d).setIdentity();
  if (n == 1) return R;
  Eigen::SparseMatrix<double> Hrr = H.bottomRightCorner(m, m);
  Eigen::MatrixXd rhs = -Eigen::MatrixXd(H.bottomLeftCorner(m, d));
  H = Eigen::SparseMatrix<double>();
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> chol;
  // CHOLMOD chooses simplicial or supernodal unless the caller needs it BLAS-free.
  chol.setMode(simplicial ? Eigen::CholmodLDLt : Eigen::CholmodAuto);
  cholmod_compute_checked(chol, Hrr, "chordal initialization");
  if (chol.info() != Eigen::Success)
    throw std::runtime_error("chordal initialization: factorization failed (disconnected graph?)");
  Eigen::MatrixXd Z = chol.solve(rhs);  // rows: d(n-1) coordinates, cols: row index a
  // d x d on the stack: no heap traffic per pose.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> Ri(d, d);
  for (Index i = 1; i < n; ++i) {
    Ri = Z.middleRows(d * (i - 1), d).transpose();  // row a of R_i = column a of Z
    project_to_rotation(Ri, R.middleCols(d * i, d));
  }
  return R;
}

std::vector<Pose> chordal_initialization(const PoseGraph& graph) {
  Eigen::MatrixXd R = chordal_rotations(graph);
  Eigen::MatrixXd t = solve_translations(graph, R);
  return assemble_poses(R, t);
}

}  // namespace tessera
