#include "io/toro_records.hpp"

#include <cmath>

namespace tessera {

Eigen::MatrixXd rotation_from_roll_pitch_yaw(double roll, double pitch, double yaw) {
  const double cr = std::cos(roll), sr = std::sin(roll);
  const double cp = std::cos(pitch), sp = std::sin(pitch);
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  Eigen::MatrixXd R(3, 3);
  R << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,  //
      sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,   //
      -sp, cp * sr, cp * cr;
  return R;
}

void toro_information_2d(const double* t, double* upper6) {
  // TORO: xx xy yy tt xt yt; g2o: xx xy xt yy yt tt.
  upper6[0] = t[0];
  upper6[1] = t[1];
  upper6[2] = t[4];
  upper6[3] = t[2];
  upper6[4] = t[5];
  upper6[5] = t[3];
}

void toro_information_3d(const double* toro21, double* upper21) {
  int k = 0;
  for (int r = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c, ++k) {
      const double scale = (r >= 3 ? 2.0 : 1.0) * (c >= 3 ? 2.0 : 1.0);
      upper21[k] = scale * toro21[k];
    }
}

}  // namespace tessera
