#include "generate/trajectory.hpp"

#include <algorithm>

namespace tessera {

Trajectory make_trajectory(TrajectoryKind kind, std::size_t n, std::uint64_t seed) {
  switch (kind) {
    case TrajectoryKind::kGrid3d:
      return make_grid3d_trajectory(n);
    case TrajectoryKind::kSphere:
      return make_sphere_trajectory(n);
    case TrajectoryKind::kTorus:
      return make_torus_trajectory(n);
    case TrajectoryKind::kCity: {
      RandomStream walk(seed, 1);
      return make_city_trajectory(n, walk);
    }
  }
  return make_grid3d_trajectory(n);
}

void normalise_candidates(std::vector<PosePair>& candidates, std::size_t n) {
  for (auto& c : candidates)
    if (c.first > c.second) std::swap(c.first, c.second);
  candidates.erase(
      std::remove_if(candidates.begin(), candidates.end(),
                     [n](const PosePair& c) { return c.second >= n || c.second - c.first < 2; }),
      candidates.end());
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
}

}  // namespace tessera
