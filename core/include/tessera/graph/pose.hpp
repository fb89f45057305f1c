#pragma once
// A rigid-body pose in SE(d), d = 2 or 3.

#include <Eigen/Core>

namespace tessera {

struct Pose {
  Eigen::MatrixXd R;  ///< d x d rotation (orthonormal, det +1).
  Eigen::VectorXd t;  ///< d translation.

  static Pose identity(int d) {
    return {Eigen::MatrixXd::Identity(d, d), Eigen::VectorXd::Zero(d)};
  }
  int dim() const { return static_cast<int>(t.size()); }
};

}  // namespace tessera
