// sphere: a spiral of rings from the south to the north pole, like the sphere2500 benchmark.
#include <algorithm>
#include <cmath>

#include "generate/geometry.hpp"
#include "generate/trajectory.hpp"

namespace tessera {

Trajectory make_sphere_trajectory(std::size_t n) {
  const std::size_t rings = std::max<std::size_t>(1, std::llround(std::sqrt(double(n))));
  const std::size_t per_ring = (n + rings - 1) / rings;
  // Consecutive poses about 1 m apart on the equator.
  const double radius = std::max(1.0, double(per_ring) / (2.0 * kPi));

  Trajectory traj;
  traj.d = 3;
  traj.poses.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    // Latitude rises steadily so that pose k + per_ring sits right "above" pose k.
    const double lat =
        kPi * ((double(k) + 0.5 * double(per_ring)) / double(rings * per_ring) - 0.5);
    const double lon = 2.0 * kPi * double(k % per_ring) / double(per_ring);
    const Eigen::Vector3d normal(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                                 std::sin(lat));
    const Eigen::Vector3d east(-std::sin(lon), std::cos(lon), 0.0);
    traj.poses.push_back({frame_from_forward_up(east, normal), radius * normal});
  }
  traj.closure_candidates.reserve(2 * n);
  for (std::size_t k = 0; k + per_ring < n; ++k) {
    traj.closure_candidates.emplace_back(k, k + per_ring);
    traj.closure_candidates.emplace_back(k, k + per_ring + 1);
  }
  normalise_candidates(traj.closure_candidates, n);
  return traj;
}

}  // namespace tessera
