#pragma once
// Small rotation helpers shared by the trajectory kinds and the noise model.

#include <Eigen/Core>

// planar_rotation(theta), the 2x2 rotation by theta, lives beside its inverse planar_angle.
#include "io/rotation_text.hpp"

namespace tessera {

constexpr double kPi = 3.14159265358979323846;

/// The right-handed frame whose x axis is `forward` and whose z axis is the part of `up`
/// orthogonal to it (both normalised). `up` must not be parallel to `forward`.
Eigen::MatrixXd frame_from_forward_up(const Eigen::Vector3d& forward, const Eigen::Vector3d& up);

/// The exponential map of so(3): the rotation by |w| about w / |w| (Rodrigues' formula,
/// with series coefficients near 0).
Eigen::Matrix3d so3_exp(const Eigen::Vector3d& w);

/// The exponential map of so(d): the rotation by angle w(0) in 2D (w has 1 entry), or by
/// |w| about w / |w| in 3D (Rodrigues' formula; w has 3 entries).
Eigen::MatrixXd rotation_exp(const Eigen::VectorXd& w);

}  // namespace tessera
