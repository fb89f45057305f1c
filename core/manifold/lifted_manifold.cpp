#include "manifold/lifted_manifold.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <Eigen/SVD>

namespace tessera {
namespace {
// d x d scratch matrices live on the stack (d <= 3): no heap traffic in per-pose loops.
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
}  // namespace

LiftedManifold::LiftedManifold(int r, int d, std::size_t n) : r_(r), d_(d), n_(n) {
  if (d < 2 || d > 3) throw std::invalid_argument("LiftedManifold: d must be 2 or 3");
  if (r < d) throw std::invalid_argument("LiftedManifold: rank r must be >= d");
}

Eigen::MatrixXd polar_factor(const Eigen::MatrixXd& A) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  return svd.matrixU() * svd.matrixV().transpose();
}

Eigen::MatrixXd LiftedManifold::project(const Eigen::MatrixXd& X) const {
  Eigen::MatrixXd out = X;
  for (std::size_t i = 0; i < n_; ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>((d_ + 1) * i);
    out.middleCols(c, d_) = polar_factor(X.middleCols(c, d_));
  }
  return out;
}

Eigen::MatrixXd LiftedManifold::tangent_project(const Eigen::MatrixXd& X,
                                                const Eigen::MatrixXd& V) const {
  Eigen::MatrixXd out = V;
  SmallMatrix S(d_, d_);
  for (std::size_t i = 0; i < n_; ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>((d_ + 1) * i);
    S.noalias() = X.middleCols(c, d_).transpose() * V.middleCols(c, d_);
    SmallMatrix sym = 0.5 * (S + S.transpose());
    out.middleCols(c, d_).noalias() -= X.middleCols(c, d_) * sym;
  }
  return out;
}

Eigen::MatrixXd LiftedManifold::retract(const Eigen::MatrixXd& X, const Eigen::MatrixXd& V) const {
  return project(X + V);
}

Eigen::MatrixXd LiftedManifold::weingarten_term(const Eigen::MatrixXd& X, const Eigen::MatrixXd& G,
                                                const Eigen::MatrixXd& V) const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(X.rows(), X.cols());
  SmallMatrix S(d_, d_);
  for (std::size_t i = 0; i < n_; ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>((d_ + 1) * i);
    S.noalias() = X.middleCols(c, d_).transpose() * G.middleCols(c, d_);
    SmallMatrix sym = 0.5 * (S + S.transpose());
    out.middleCols(c, d_).noalias() = V.middleCols(c, d_) * sym;
  }
  return out;
}

double LiftedManifold::distance_from_manifold(const Eigen::MatrixXd& X) const {
  double worst = 0.0;
  for (std::size_t i = 0; i < n_; ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>((d_ + 1) * i);
    SmallMatrix S = X.middleCols(c, d_).transpose() * X.middleCols(c, d_);
    worst = std::max(worst, (S - SmallMatrix::Identity(d_, d_)).norm());
  }
  return worst;
}

}  // namespace tessera
