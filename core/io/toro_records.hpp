#pragma once
// The values of TORO records (VERTEX2 / EDGE2 / VERTEX3 / EDGE3) in the form the g2o
// reader works with. TORO writes rotations as roll-pitch-yaw angles and lists its
// information values in its own order; docs/file-formats.md shows both.

#include <Eigen/Core>

namespace tessera {

/// R = Rz(yaw) Ry(pitch) Rx(roll), TORO's (and most robotics code's) convention.
Eigen::MatrixXd rotation_from_roll_pitch_yaw(double roll, double pitch, double yaw);

/// EDGE2's six information values (Ixx Ixy Iyy Itt Ixt Iyt) as g2o's upper triangle
/// (I11 I12 I13 I22 I23 I33).
void toro_information_2d(const double* toro6, double* upper6);

/// EDGE3's 21 values (row-major upper triangle over x y z roll pitch yaw) as g2o's
/// EDGE_SE3:QUAT triangle, whose rotation error is the quaternion's vector part (about half
/// the angle): the rotation block is scaled by 4 and the cross block by 2, so that the same
/// error costs the same in both forms.
void toro_information_3d(const double* toro21, double* upper21);

}  // namespace tessera
