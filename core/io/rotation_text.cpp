#include "io/rotation_text.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace tessera {

double planar_angle(const Eigen::MatrixXd& R) {
  return std::atan2(R(1, 0), R(0, 0));
}

std::array<double, 4> unit_quaternion(const Eigen::MatrixXd& R) {
  Eigen::Matrix3d R3 = Eigen::Matrix3d::Identity();
  if (R.rows() == 2)
    R3.topLeftCorner<2, 2>() = R;
  else
    R3 = R;
  Eigen::Quaterniond q(R3);
  q.normalize();
  const double s = q.w() < 0 ? -1.0 : 1.0;
  return {s * q.x(), s * q.y(), s * q.z(), s * q.w()};
}

}  // namespace tessera
