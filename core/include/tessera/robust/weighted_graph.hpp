#pragma once
// The graphs a robust solve optimises: every measurement scaled by its weight (the inner
// solves of GNC) and the inlier graph without the rejected ones (the final certified solve).

#include <cstddef>
#include <cstdint>
#include <tessera/graph/pose_graph.hpp>
#include <utility>
#include <vector>

namespace tessera {

/// Weights below this are raised to it in weighted_graph(): a zero-weight edge stays in the
/// inner solves so that the graph keeps its connectivity (a cut-off part would leave the
/// translation solve singular), at a pull 1e-10 times its plain weight.
constexpr double kMinInnerWeight = 1e-10;

/// `m` with kappa and tau multiplied by max(weight, kMinInnerWeight): one measurement of an
/// inner solve.
Measurement weighted_measurement(Measurement m, double weight);

/// `graph` with every measurement's kappa and tau multiplied by max(weights[e],
/// kMinInnerWeight), and `initial` = `initial` (the warm start). weights.size() must equal
/// graph.num_measurements() (std::invalid_argument otherwise).
PoseGraph weighted_graph(const PoseGraph& graph, const std::vector<double>& weights,
                         const std::vector<Pose>& initial);

/// `graph` without the measurements whose indices are in `rejected` (sorted ascending), with
/// `initial` as its initial guess.
PoseGraph inlier_graph(const PoseGraph& graph, const std::vector<std::size_t>& rejected,
                       const std::vector<Pose>& initial);

/// The endpoints of `structure` (one per measurement, file order) without those whose indices
/// are in `rejected` (ascending): the structure of inlier_graph()'s graph.
std::vector<std::pair<std::uint32_t, std::uint32_t>> inlier_structure(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint64_t>& rejected);

/// `graph` with only the measurements flagged in `keep` (one flag per measurement), without an
/// initial guess: the known inliers' graph, whose connectivity decides whether they can start
/// or test a robust solve.
PoseGraph known_subgraph(const PoseGraph& graph, const std::vector<bool>& keep);

/// Throws InputError (naming graph.source) when `inliers`, the graph left after `rejected`
/// measurements were removed, no longer connects its poses: every robust solve ends with a
/// clear message then, never with a collapsed estimate.
void require_connected_inliers(const PoseGraph& graph, const PoseGraph& inliers,
                               std::size_t rejected);

}  // namespace tessera
