#pragma once
// Options of the synthetic multi-robot pose-graph generator (see docs/generator.md).

#include <cstddef>
#include <cstdint>
#include <string>

namespace tessera {

/// Ground-truth trajectory shapes used in the PGO literature.
enum class TrajectoryKind {
  kGrid3d,  ///< Lawnmower path through a cube lattice (like grid3D); closures to lattice
            ///< neighbours.
  kSphere,  ///< Spiral of rings on a sphere (like sphere2500); closures between adjacent rings.
  kTorus,   ///< Spiral of loops around a torus (like torus3D); closures between adjacent loops.
  kCity,    ///< 2D random walk on a Manhattan street grid (like M3500 / city10000); closures on
            ///< revisits.
};

/// Which wrong loop closures the generator adds (GeneratorOptions::outlier_fraction).
enum class OutlierKind {
  kRandom,      ///< Random pose pairs with random relative poses.
  kGroup,       ///< Groups of mutually consistent wrong closures (the harder case).
  kInterRobot,  ///< Random, with the two ends on different robots.
};

/// "random", "group" or "inter-robot".
const char* outlier_kind_name(OutlierKind kind);
/// Inverse of outlier_kind_name; throws InputError listing the valid names otherwise.
OutlierKind parse_outlier_kind(const std::string& name);

/// "grid3d", "sphere", "torus" or "city".
const char* trajectory_kind_name(TrajectoryKind kind);
/// Inverse of trajectory_kind_name; throws InputError listing the valid names otherwise.
TrajectoryKind parse_trajectory_kind(const std::string& name);

struct GeneratorOptions {
  TrajectoryKind kind = TrajectoryKind::kGrid3d;
  /// Number of poses n, in [2, 10,000,000]. Ids are 0..n-1.
  std::size_t num_poses = 1000;
  /// Number of robots N, in [1, num_poses]. Robot r owns ids [r n / N, (r + 1) n / N).
  std::size_t num_robots = 1;
  /// Probability in [0, 1] that a candidate loop closure between two poses of the same robot
  /// (places the trajectory revisits or passes next to) becomes a measurement.
  double loop_closure_probability = 0.5;
  /// Same, for candidates between poses of different robots. Independently of it, robot r's
  /// last pose and robot r+1's first pose are always linked (a rendezvous), which keeps the
  /// graph connected.
  double inter_robot_closure_probability = 0.5;
  /// When > 0, at most this many sampled loop closures (intra + inter, rendezvous links not
  /// counted), a uniformly random subset of the accepted ones. 0 means no cap.
  std::size_t max_loop_closures = 0;
  /// Rotation noise: standard deviation in radians of each component of the tangent vector
  /// w in R_ij = R_i^T R_j Exp(w) (one component in 2D, three in 3D). In [0, 1].
  double rotation_noise = 0.01;
  /// Translation noise: standard deviation in metres of each component of the translation
  /// error, added in the frame of pose i. In [0, 100].
  double translation_noise = 0.05;
  /// Wrong loop closures to add, as a fraction of the graph's loop closures (intra, inter and
  /// rendezvous), in [0, 0.9]: round(F * loop closures) measurements, appended after the clean
  /// ones from their own random stream, so the graph without them is the F = 0 graph.
  double outlier_fraction = 0.0;
  /// What the added closures look like; kInterRobot needs num_robots >= 2.
  OutlierKind outlier_kind = OutlierKind::kRandom;
  /// Seeds every random choice; the same options give byte-identical graphs.
  std::uint64_t seed = 1;

  /// Throws InputError naming the first field that is out of range.
  void validate() const;
};

}  // namespace tessera
