#pragma once
// Ground-truth trajectories for the generator: one file per kind (grid3d_trajectory.cpp,
// sphere_trajectory.cpp, torus_trajectory.cpp, city_trajectory.cpp).

#include <cstddef>
#include <tessera/generate/generator_options.hpp>
#include <tessera/graph/pose.hpp>
#include <utility>
#include <vector>

#include "generate/random_stream.hpp"

namespace tessera {

/// A pair of pose ids (a < b) close enough in space for a loop closure.
using PosePair = std::pair<std::size_t, std::size_t>;

struct Trajectory {
  int d = 3;
  /// poses[k] is the true pose of id k; consecutive poses are about 1 m apart.
  std::vector<Pose> poses;
  /// Places the path revisits or passes next to: a < b, b - a > 1 (never an odometry
  /// step), sorted, no duplicates. The generator samples loop closures from them.
  std::vector<PosePair> closure_candidates;
};

/// Lawnmower path through the smallest s x s x s lattice (1 m spacing) with s^3 >= n.
/// Candidates: every lattice-neighbour pair that is not an odometry step.
Trajectory make_grid3d_trajectory(std::size_t n);
/// Spiral over about sqrt(n) rings of a sphere. Candidates: each pose with the poses at the
/// same and the next longitude on the next ring.
Trajectory make_sphere_trajectory(std::size_t n);
/// Spiral of loops around the tube of a torus, the loops advancing around the main circle.
/// Candidates: each pose with the same and next pose on the next loop (the last loop
/// wraps to the first).
Trajectory make_torus_trajectory(std::size_t n);
/// 2D random walk (no U-turns) on a square Manhattan street grid sized so that places are
/// revisited about three times. Candidates: each revisit with the first and the latest
/// earlier visit of the same place. The walk draws from `random`.
Trajectory make_city_trajectory(std::size_t n, RandomStream& random);

/// The trajectory of `kind`; random choices (city only) come from stream 1 of `seed`.
Trajectory make_trajectory(TrajectoryKind kind, std::size_t n, std::uint64_t seed);

/// Sorts candidates and drops duplicates and pairs that are not (a < b - 1, b < n).
void normalise_candidates(std::vector<PosePair>& candidates, std::size_t n);

}  // namespace tessera
