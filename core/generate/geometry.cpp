#include "generate/geometry.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace tessera {

Eigen::MatrixXd frame_from_forward_up(const Eigen::Vector3d& forward, const Eigen::Vector3d& up) {
  const Eigen::Vector3d x = forward.normalized();
  const Eigen::Vector3d z = (up - up.dot(x) * x).normalized();
  Eigen::MatrixXd R(3, 3);
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return R;
}

Eigen::Matrix3d so3_exp(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  Eigen::Matrix3d K;
  K << 0, -w(2), w(1), w(2), 0, -w(0), -w(1), w(0), 0;
  // Series coefficients below 1e-8 rad: sin(a)/a and (1-cos a)/a^2 lose all precision there.
  const double a = angle < 1e-8 ? 1.0 - angle * angle / 6.0 : std::sin(angle) / angle;
  const double b =
      angle < 1e-8 ? 0.5 - angle * angle / 24.0 : (1.0 - std::cos(angle)) / (angle * angle);
  return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

Eigen::MatrixXd rotation_exp(const Eigen::VectorXd& w) {
  if (w.size() == 1) return planar_rotation(w(0));
  return so3_exp(Eigen::Vector3d(w));
}

}  // namespace tessera
