#pragma once
// One relative-pose measurement between two poses, with the scalar weights of the
// isotropic-noise model used by SE-Sync and the reference optima (../shared/reference).

#include <Eigen/Core>
#include <cstddef>

namespace tessera {

struct Measurement {
  std::size_t i = 0;  ///< Source pose id (the measurement is expressed in the frame of pose i).
  /// Target pose id. i != j. Edges written backwards in a file are kept as read.
  std::size_t j = 0;
  Eigen::MatrixXd R;   ///< Measured rotation R_ij (d x d, in SO(d)).
  Eigen::VectorXd t;   ///< Measured translation t_ij (d).
  double kappa = 1.0;  ///< Rotation weight (> 0).
  double tau = 1.0;    ///< Translation weight (> 0).

  int dim() const { return static_cast<int>(t.size()); }
};

}  // namespace tessera
