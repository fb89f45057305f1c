#pragma once
// Rotation parameterisations used by the text formats (g2o, TUM).

#include <Eigen/Core>
#include <array>

namespace tessera {

/// The 2x2 rotation [[cos, -sin], [sin, cos]] by `theta` radians (how g2o's 2D records
/// give a rotation; also the generator's planar rotation).
Eigen::MatrixXd planar_rotation(double theta);

/// The angle theta in (-pi, pi] of a 2x2 rotation [[cos, -sin], [sin, cos]] (the inverse
/// of planar_rotation).
double planar_angle(const Eigen::MatrixXd& R);

/// The 3x3 matrix of the quaternion (x, y, z, w) by the unit-quaternion formula. It is a
/// rotation only for a unit quaternion; for any other it is what SE-Sync computes from the
/// same numbers (the reference optima of raw-quaternion files depend on that).
Eigen::MatrixXd rotation_from_quaternion(double x, double y, double z, double w);

/// The unit quaternion (qx, qy, qz, qw) of a 3x3 rotation, with qw >= 0 so that each
/// rotation has one written form. A 2x2 rotation is taken as a rotation about z.
std::array<double, 4> unit_quaternion(const Eigen::MatrixXd& R);

}  // namespace tessera
