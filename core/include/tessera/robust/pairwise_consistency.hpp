#pragma once
// Pairwise consistency maximisation before GNC (`--robust pcm-gnc`; after Mangelson, Dominic,
// Eustice, Vasudevan, "Pairwise consistent measurement set maximization for robust
// multi-robot map merging", ICRA 2018): two candidate closures are consistent when the cycle
// they close with the odometry between their ends is near the identity, measured against
// the noise the cycle accumulates; the largest set of mutually consistent candidates is kept
// and the rest start GNC with weight 0. Wrong closures that agree with each other (a group
// between two look-alike places) pass a residual test one by one, but they disagree with
// the true closures elsewhere, and the true ones are the larger consistent set.

#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct PairwiseConsistencyResult {
  std::vector<std::size_t> candidates;    ///< Tested measurements (not known inliers), ascending.
  std::vector<std::size_t> inconsistent;  ///< Candidates outside the kept set, ascending.
  std::size_t consistent_pairs = 0;       ///< Pairs that passed the test.
};

/// Tests every pair of candidates (measurements with known[e] false) against the odometry
/// `chain` poses (the known inliers' initialization, which must connect the poses) and keeps
/// the largest mutually consistent set found by a greedy clique search from every candidate.
/// A pair passes when its cycle residual, whitened by the summed variances of the two closures
/// and the odometry between their ends (the isotropic model: rotation variance 1/(2 kappa),
/// translation variance 1/tau per measurement, plus the rotation drift times the lever arm),
/// is at most c2 (the TLS bound).
PairwiseConsistencyResult pairwise_consistency(const PoseGraph& graph,
                                               const std::vector<bool>& known,
                                               const std::vector<Pose>& chain, double c2);

}  // namespace tessera
