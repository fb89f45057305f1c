#pragma once
// Pieces of a growing graph that meet. Until a measurement links them, two pieces of the graph
// (two robots that have not met, a robot's first poses started from its front end's guess) are
// separate problems, each fixed only up to its own rigid motion of the lifted space (an element
// of O(r) and a translation): their relative frame is whatever the guesses and the solver left,
// and the front ends' guesses drift without bound along a long trajectory (a random rotation
// after a few thousand poses). The first measurement that links them would then enter with an
// arbitrary residual, and the solver would have to turn a whole piece through the lifted space
// from a start no batch solve would use: on long runs that can end at a critical point of the
// relaxation far from the optimum. Instead, when a measurement first links two pieces, the
// smaller piece is moved rigidly so that this measurement has zero residual, as composition
// places a new pose (estimate_extension.hpp). A rigid motion of a whole piece leaves every
// residual inside it, hence its cost and its gradient's norm, as they were: the merged problem
// starts exactly where the two separate ones were, joined by the first link's own measurement.

#include <Eigen/Core>
#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// What one ComponentAlignment::absorb did.
struct ComponentMerges {
  std::size_t merges = 0;       ///< Measurements that linked two pieces of >= 2 poses each.
  std::size_t poses_moved = 0;  ///< Poses of the smaller pieces, moved rigidly.
};

/// Tracks the connected pieces of a graph that only grows (poses and measurements appended)
/// and aligns pieces when they meet. Every holder that feeds it the same graph and iterate
/// moves the same poses in the same way (the DDS agents each hold one).
class ComponentAlignment {
 public:
  /// Reads the measurements of `graph` added since the last call, in graph order. A measurement
  /// between two pieces of at least two poses each moves the smaller one (fewer poses; on a tie
  /// the one holding the measurement's j) rigidly in `X` (r x (d+1) graph.num_poses, lifted,
  /// every pose already valued: call after extend_estimate) so that it has zero residual; a
  /// single pose joins as it is (composition placed it, or it is a robot's first pose).
  /// Throws std::invalid_argument when `X` does not fit the graph.
  /// `align` false: only tracks the pieces (X is not changed, nothing is counted as moved).
  ComponentMerges absorb(const PoseGraph& graph, Eigen::MatrixXd& X, bool align = true);

  /// Pieces among the poses seen so far (a pose no measurement touches is a piece of its own).
  std::size_t pieces() const { return pieces_; }

 private:
  std::size_t root(std::size_t k);
  void grow(std::size_t n);

  std::size_t seen_measurements_ = 0;
  std::size_t pieces_ = 0;
  std::vector<std::size_t> parent_;
  // Poses of each piece, held by its root only (the smaller list joins the larger one).
  std::vector<std::vector<std::size_t>> members_;
};

/// An orthogonal r x r matrix Q with det Q = +1 and Q A = B, for A, B r x d with orthonormal
/// columns and r > d (the rotation a piece's lifted frame needs); for r = d, Q = B A^T.
Eigen::MatrixXd lifted_rotation_between(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B);

}  // namespace tessera
