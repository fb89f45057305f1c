// torus: loops around the tube of a torus that advance around its main circle, like torus3D.
#include <algorithm>
#include <cmath>

#include "generate/geometry.hpp"
#include "generate/trajectory.hpp"

namespace tessera {

Trajectory make_torus_trajectory(std::size_t n) {
  // About twice as many loops as poses per loop, as in torus3D (5000 poses, 100 per loop).
  const std::size_t per_loop = std::max<std::size_t>(3, std::llround(std::sqrt(double(n) / 2.0)));
  const double loops = double(n) / double(per_loop);
  const double tube_radius = double(per_loop) / (2.0 * kPi);  // 1 m steps around the tube
  const double main_radius = std::max(2.0 * tube_radius, loops / (2.0 * kPi));

  Trajectory traj;
  traj.d = 3;
  traj.poses.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double u = 2.0 * kPi * double(k) / double(n);         // around the main circle
    const double v = 2.0 * kPi * double(k) / double(per_loop);  // around the tube
    const Eigen::Vector3d normal(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
    const Eigen::Vector3d forward(-std::sin(v) * std::cos(u), -std::sin(v) * std::sin(u),
                                  std::cos(v));
    const Eigen::Vector3d centre(main_radius * std::cos(u), main_radius * std::sin(u), 0.0);
    traj.poses.push_back({frame_from_forward_up(forward, normal), centre + tube_radius * normal});
  }
  traj.closure_candidates.reserve(2 * n + per_loop);
  for (std::size_t k = 0; k + per_loop < n; ++k) {
    traj.closure_candidates.emplace_back(k, k + per_loop);
    traj.closure_candidates.emplace_back(k, k + per_loop + 1);
  }
  // The last loop lies next to the first: link it to the pose at the same tube angle there.
  const std::size_t shift = n % per_loop;
  for (std::size_t k = n > per_loop ? n - per_loop : 0; k < n; ++k) {
    const std::size_t j = k + per_loop + shift - n;
    if (j < n) traj.closure_candidates.emplace_back(j, k);
  }
  normalise_candidates(traj.closure_candidates, n);
  return traj;
}

}  // namespace tessera
