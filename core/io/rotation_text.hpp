#pragma once
// Rotation parameterisations used by the text formats (g2o, TUM).

#include <Eigen/Core>
#include <array>

namespace tessera {

/// The angle theta in (-pi, pi] of a 2x2 rotation [[cos, -sin], [sin, cos]].
double planar_angle(const Eigen::MatrixXd& R);

/// The unit quaternion (qx, qy, qz, qw) of a 3x3 rotation, with qw >= 0 so that each
/// rotation has one written form. A 2x2 rotation is taken as a rotation about z.
std::array<double, 4> unit_quaternion(const Eigen::MatrixXd& R);

}  // namespace tessera
