#include "distributed/rigid_retraction.hpp"

#include <cmath>

namespace tessera {

namespace {

// exp(W) and V(W) for a 2 x 2 skew W = [0 -th; th 0].
void exp_and_jacobian_2d(const Eigen::MatrixXd& W, Eigen::MatrixXd& Q, Eigen::MatrixXd& V) {
  const double th = W(1, 0);
  const bool small = std::abs(th) < 1e-6;  // series: sin(th)/th, (1 - cos(th))/th
  const double a = small ? 1.0 - th * th / 6 : std::sin(th) / th;
  const double b = small ? th / 2 - th * th * th / 24 : (1.0 - std::cos(th)) / th;
  const double c = std::cos(th), s = std::sin(th);
  Q = Eigen::Matrix2d{{c, -s}, {s, c}};
  V = Eigen::Matrix2d{{a, -b}, {b, a}};
}

// exp(W) = I + A W + B W^2 (Rodrigues) and V(W) = I + B W + C W^2 for a 3 x 3 skew W.
void exp_and_jacobian_3d(const Eigen::MatrixXd& W, Eigen::MatrixXd& Q, Eigen::MatrixXd& V) {
  const double phi = std::sqrt(W(2, 1) * W(2, 1) + W(0, 2) * W(0, 2) + W(1, 0) * W(1, 0));
  const Eigen::Matrix3d W2 = W * W;
  double A, B, C;
  if (phi < 1e-4) {  // the series to the order that keeps them exact in double precision
    const double p2 = phi * phi;
    A = 1.0 - p2 / 6 + p2 * p2 / 120;
    B = 0.5 - p2 / 24 + p2 * p2 / 720;
    C = 1.0 / 6 - p2 / 120 + p2 * p2 / 5040;
  } else {
    A = std::sin(phi) / phi;
    B = (1.0 - std::cos(phi)) / (phi * phi);
    C = (phi - std::sin(phi)) / (phi * phi * phi);
  }
  Q = Eigen::Matrix3d::Identity() + A * W + B * W2;
  V = Eigen::Matrix3d::Identity() + B * W + C * W2;
}

}  // namespace

Eigen::MatrixXd retract_rigid(const LiftedManifold& manifold, int d, const Eigen::MatrixXd& X,
                              const Eigen::MatrixXd& s) {
  if (X.rows() != d || (d != 2 && d != 3)) return manifold.retract(X, s);
  Eigen::MatrixXd Xt(X.rows(), X.cols());
  const Eigen::Index n = X.cols() / (d + 1);
  Eigen::MatrixXd W, Q, V;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index c = i * (d + 1);
    const auto R = X.middleCols(c, d);
    const auto t = X.col(c + d);
    W = s.middleCols(c, d) * R.transpose();
    W = 0.5 * (W - W.transpose()).eval();  // skew already for a tangent s; drop round-off
    const Eigen::VectorXd v = s.col(c + d) - W * t;
    if (d == 2)
      exp_and_jacobian_2d(W, Q, V);
    else
      exp_and_jacobian_3d(W, Q, V);
    Xt.middleCols(c, d).noalias() = Q * R;
    Xt.col(c + d).noalias() = Q * t + V * v;
  }
  return Xt;
}

}  // namespace tessera
