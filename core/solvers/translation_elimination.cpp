#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <stdexcept>
#include <tessera/solvers/translation_elimination.hpp>

#include "solvers/cholmod_checked.hpp"

namespace tessera {

struct TranslationElimination::Factor {
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>> llt;
};

TranslationElimination::TranslationElimination(int d, std::size_t num_poses,
                                               const std::vector<Measurement>& measurements,
                                               bool simplicial)
    : d_(d), n_(num_poses), edges_(measurements), factor_(std::make_unique<Factor>()) {
  if (n_ < 2) return;  // a single pose: nothing to solve
  // Unknowns p_1..p_{n-1} (pose 0 fixed): variable k is pose k+1.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(edges_.size() * 4);
  for (const auto& m : edges_) {
    const long vi = static_cast<long>(m.i) - 1, vj = static_cast<long>(m.j) - 1;
    if (vi >= 0) trip.emplace_back(vi, vi, m.tau);
    if (vj >= 0) trip.emplace_back(vj, vj, m.tau);
    if (vi >= 0 && vj >= 0) {
      trip.emplace_back(vi, vj, -m.tau);
      trip.emplace_back(vj, vi, -m.tau);
    }
  }
  const Eigen::Index m = static_cast<Eigen::Index>(n_ - 1);
  Eigen::SparseMatrix<double> L(m, m);
  L.setFromTriplets(trip.begin(), trip.end());
  factor_->llt.setMode(simplicial ? Eigen::CholmodLDLt : Eigen::CholmodAuto);
  cholmod_compute_checked(factor_->llt, L, "TranslationElimination");
  if (factor_->llt.info() != Eigen::Success)
    throw std::runtime_error(
        "TranslationElimination: Laplacian factorization failed (disconnected graph?)");
}

TranslationElimination::~TranslationElimination() = default;

void TranslationElimination::optimize_translations(Eigen::MatrixXd& X) const {
  if (n_ < 2) return;
  const Eigen::Index r = X.rows();
  const Eigen::Index w = d_ + 1;
  // Normal equations with pose 0 at the origin: L P = B, rows = poses 1..n-1, columns = the r
  // coordinates. Edge e contributes tau c to B_j and -tau c to B_i with c = Y_i t_ij.
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n_ - 1), r);
  for (const auto& m : edges_) {
    const double* Yi = X.data() + r * w * static_cast<Eigen::Index>(m.i);
    for (Eigen::Index a = 0; a < r; ++a) {
      double c = 0.0;
      for (int k = 0; k < d_; ++k) c += Yi[k * r + a] * m.t(k);
      c *= m.tau;
      if (m.i > 0) B(static_cast<Eigen::Index>(m.i) - 1, a) -= c;
      if (m.j > 0) B(static_cast<Eigen::Index>(m.j) - 1, a) += c;
    }
  }
  const Eigen::MatrixXd P = factor_->llt.solve(B);
  const Eigen::VectorXd p0 = X.col(d_);
  for (std::size_t i = 1; i < n_; ++i)
    X.col(w * static_cast<Eigen::Index>(i) + d_) =
        p0 + P.row(static_cast<Eigen::Index>(i) - 1).transpose();
}

}  // namespace tessera
