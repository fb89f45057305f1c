#pragma once
// Kept loop closures that run side by side, as candidates for a joint cut (the centralized
// cluster probes, RobustOptions::cluster_probes). Perceptual aliasing makes wrong closures in
// runs: poses a, a+1, ... of one stretch matched to b, b+1, ... of a look-alike one, all
// measuring one wrong rigid motion. Such a run fits itself: one bend of the map between the two
// stretches satisfies every member, so no residual test cuts them one at a time, and the true
// closures of that stretch, which disagree with the bend, are cut instead. The cut closures
// near a run are what points at it.

#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct ClosureClusterOptions {
  /// Two kept closures (i, j), (i', j') (i < j, i' < j') are in one cluster when |i - i'| and
  /// |j - j'| are both at most this many pose ids, >= 1. 2: a run of closures between two
  /// stretches has consecutive members one id apart, and a gap of one missed match does not
  /// split it.
  int window = 2;
  /// Fewest closures of a cluster, >= 2: a single wrong closure is the re-check passes' case.
  std::size_t min_size = 2;
  /// A rejected closure points at a cluster when one of its ends lies within this many pose ids
  /// of one of the cluster's two stretches, >= 0. 20: on intel with group outliers the true
  /// closures cut beside a kept wrong run end within 40 ids of its stretches.
  int near = 20;
  /// Fewest rejected closures near a cluster for it to be listed, >= 0 (0 = every cluster).
  std::size_t min_rejected_near = 1;
  /// Throws InputError naming the first bad field.
  void validate() const;
};

struct ClosureCluster {
  std::vector<std::size_t> members;  ///< Measurement indices, ascending.
  std::size_t rejected_near = 0;     ///< Rejected closures with an end near its stretches.
  /// Rejected closures of its own run: within the window of a member at both ends (a run whose
  /// other members GNC cut, so part of it was already judged wrong).
  std::size_t rejected_in_run = 0;
  /// Its two stretches: the id ranges of its members' lower and upper ends.
  std::size_t lo_first = 0, lo_last = 0, hi_first = 0, hi_last = 0;
};

/// Runs cut together by one probe: the clusters and their members (ascending).
struct ClusterUnion {
  std::vector<ClosureCluster> parts;
  std::vector<std::size_t> members;
};

/// Every cluster of `clusters` that GNC partly cut (rejected_in_run > 0), as one probe; empty
/// when there are fewer than two. Wrong runs that share stretches hold one bend together, and
/// cutting one of them alone leaves the bend to the others (intel, group 0.75).
ClusterUnion partly_cut_runs(const std::vector<ClosureCluster>& clusters);

/// True when a stretch of `a` and a stretch of `b` lie within `near` pose ids of each other: two
/// runs that share a stretch can hold one bend of the map together.
bool clusters_meet(const ClosureCluster& a, const ClosureCluster& b, int near);

/// The clusters of the kept closures (known[e] false, e not in `rejected`, which is ascending)
/// with at least options.min_size members and at least options.min_rejected_near rejected
/// closures near them. Order: the runs with a rejected member of their own first (GNC cut the
/// rest of such a run: the strongest sign of a wrong one), then longer first (a longer run holds
/// a bend more firmly), then most rejected_near first, then lower first member.
std::vector<ClosureCluster> closure_clusters(const PoseGraph& graph, const std::vector<bool>& known,
                                             const std::vector<std::size_t>& rejected,
                                             const ClosureClusterOptions& options);

}  // namespace tessera
