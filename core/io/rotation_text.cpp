#include "io/rotation_text.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace tessera {

Eigen::MatrixXd planar_rotation(double theta) {
  Eigen::MatrixXd R(2, 2);
  const double c = std::cos(theta), s = std::sin(theta);
  R << c, -s, s, c;
  return R;
}

double planar_angle(const Eigen::MatrixXd& R) {
  return std::atan2(R(1, 0), R(0, 0));
}

Eigen::MatrixXd rotation_from_quaternion(double x, double y, double z, double w) {
  const double tx = 2 * x, ty = 2 * y, tz = 2 * z;
  const double twx = tx * w, twy = ty * w, twz = tz * w;
  const double txx = tx * x, txy = ty * x, txz = tz * x;
  const double tyy = ty * y, tyz = tz * y, tzz = tz * z;
  Eigen::MatrixXd R(3, 3);
  R << 1 - (tyy + tzz), txy - twz, txz + twy,  //
      txy + twz, 1 - (txx + tzz), tyz - twx,   //
      txz - twy, tyz + twx, 1 - (txx + tyy);
  return R;
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
