#pragma once
// The synthetic multi-robot pose-graph generator behind `tessera generate`
// (docs/generator.md describes the trajectories, noise model and weights).

#include <cstddef>
#include <tessera/generate/generator_options.hpp>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct GeneratorResult {
  /// Noisy measurements: first the chain (k, k+1) for k = 0..n-2 -- odometry inside a robot,
  /// a rendezvous link where one robot's range ends and the next begins -- then the sampled
  /// loop closures sorted by (i, j), always i < j, then the wrong closures (`outliers`). `initial`
  /// is the chain composed from pose 0's true pose (odometry per robot, robots joined by their
  /// rendezvous links).
  PoseGraph graph;
  std::vector<Pose> ground_truth;     ///< True pose of every id.
  std::vector<std::size_t> robot_of;  ///< Robot of every id (contiguous ranges).
  std::size_t odometry_edges = 0;     ///< Chain edges inside one robot.
  std::size_t rendezvous_edges = 0;   ///< Chain edges between robots r and r+1 (N - 1).
  std::size_t intra_robot_closures = 0;
  std::size_t inter_robot_closures = 0;  ///< Sampled ones, rendezvous links not included.
  /// Indices in graph.measurements of the added wrong closures (options.outlier_fraction):
  /// always the last ones, in order. Not counted in the closure counts above.
  std::vector<std::size_t> outliers;

  /// All non-odometry edges: intra + inter-robot closures + rendezvous links.
  std::size_t loop_closures() const {
    return intra_robot_closures + inter_robot_closures + rendezvous_edges;
  }
};

/// Generates the graph described by `options` (validated first: InputError on a bad field).
/// Deterministic: the same options give the same result on every platform. The graph is
/// always connected. Time and memory are linear in the number of poses (a million 3D poses
/// take about a second and well under 1 GB).
GeneratorResult generate_pose_graph(const GeneratorOptions& options);

}  // namespace tessera
