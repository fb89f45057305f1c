#pragma once
// Least-squares alignment of two point sets (Umeyama 1991): the similarity or rigid motion
// that maps `from` onto `to` best.

#include <Eigen/Core>

namespace tessera {

enum class AlignMode { kSe3, kSim3, kNone };

/// "se3", "sim3" or "none".
const char* align_mode_name(AlignMode mode);
/// Inverse of align_mode_name; throws InputError naming the option otherwise.
AlignMode parse_align_mode(const std::string& name);

struct Alignment {
  Eigen::MatrixXd R;  ///< d x d rotation.
  Eigen::VectorXd t;  ///< d translation.
  double scale = 1;   ///< 1 unless kSim3.
};

/// The motion y = scale R x + t minimising sum |to_k - (scale R from_k + t)|^2 over the
/// columns of `from` and `to` (d x n, d = 2 for SE(2), 3 for SE(3)); identity for kNone.
/// Needs n >= 1 (n >= d for a unique rotation).
Alignment umeyama_alignment(const Eigen::MatrixXd& from, const Eigen::MatrixXd& to, AlignMode mode);

}  // namespace tessera
