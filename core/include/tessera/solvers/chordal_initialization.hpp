#pragma once
// Chordal initialization: relax the rotations to unconstrained d x d matrices, solve the
// resulting sparse linear least-squares problem (CHOLMOD; pose 0 anchored at identity),
// project each block onto SO(d), then solve the translations optimally for those rotations.

#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// One pose per graph pose: the rotations of chordal_rotations (pose 0 = identity) and the
/// translations that are optimal for them. Throws std::runtime_error when the rotation system
/// cannot be factored (a measurement graph that is not connected).
std::vector<Pose> chordal_initialization(const PoseGraph& graph);

/// Only the rotations, d x dn (the same ones chordal_initialization uses). `simplicial`: factor
/// simplicially (no BLAS calls), for a caller that runs a supernodal factorization on another
/// thread at the same time (the serial OpenBLAS build has no locks); false: CHOLMOD chooses.
Eigen::MatrixXd chordal_rotations(const PoseGraph& graph, bool simplicial = false);

}  // namespace tessera
