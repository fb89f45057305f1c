#include "distributed/gauge_space.hpp"

#include <stdexcept>

#include "util/frobenius_inner.hpp"

namespace tessera {

namespace {

// Column k of V at the poses P (d x (d+1) n): Omega P for a rotation generator (rotation and
// translation alike: the world turns about its origin), e_j in the translation columns else.
Eigen::MatrixXd gauge_column(int d, int k, const Eigen::MatrixXd& P) {
  const int w = d + 1;
  const int rotations = d * (d - 1) / 2;
  Eigen::MatrixXd v = Eigen::MatrixXd::Zero(P.rows(), P.cols());
  if (k < rotations) {
    int a = 0, b = 1;  // the k-th pair a < b
    for (int n = 0; n < k; ++n)
      if (++b == d) b = ++a + 1;
    Eigen::MatrixXd omega = Eigen::MatrixXd::Zero(d, d);
    omega(a, b) = -1.0;
    omega(b, a) = 1.0;
    v = omega * P;
  } else {
    const int j = k - rotations;
    for (Eigen::Index i = 0; i < P.cols() / w; ++i) v(j, i * w + w - 1) = 1.0;
  }
  return v;
}

}  // namespace

GaugeSpace::GaugeSpace(int d, const Eigen::MatrixXd& X, const Eigen::MatrixXd& Xn) {
  if (X.rows() != d || Xn.rows() != d)
    throw std::invalid_argument("GaugeSpace: not a rank-d point");
  const int k = d * (d + 1) / 2;
  for (int c = 0; c < k; ++c) {
    own_.push_back(gauge_column(d, c, X));
    neighbours_.push_back(gauge_column(d, c, Xn));
  }
}

void GaugeSpace::dot(const Eigen::MatrixXd& v, double* out) const {
  for (std::size_t c = 0; c < own_.size(); ++c) out[c] = frobenius_inner(own_[c], v);
}

void GaugeSpace::subtract(const Eigen::VectorXd& c, Eigen::MatrixXd& v) const {
  for (std::size_t k = 0; k < own_.size(); ++k) v -= c(static_cast<Eigen::Index>(k)) * own_[k];
}

}  // namespace tessera
