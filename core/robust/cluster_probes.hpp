#pragma once
// The search of the centralized probes after the re-check passes (GncCentralizedOptions::
// cluster_probes, RobustOptions::probe_return_ratio): which set to try next, and when to stop.
// A probe cuts a run of kept closures (closure_clusters.hpp), or several runs that share a
// stretch, or takes back rejected closures just beyond the bound (all of them together, then one
// at a time); the caller solves the kept set from there (with the re-check passes) and the result
// stays only when the TLS cost over every measurement falls. Every kept probe is a descent step
// of the TLS cost; a refused one changes nothing.

#include <cstddef>
#include <functional>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/robust/closure_clusters.hpp>
#include <vector>

namespace tessera {

/// Where a probe's solve ended: its rejected set (ascending) and poses.
struct ClusterProbeTrial {
  std::vector<std::size_t> rejected;
  std::vector<Pose> poses;
};

struct ClusterProbeCounts {
  int probes = 0;            ///< Probes run.
  int kept = 0;              ///< Of those, the ones that lowered the TLS cost and stayed.
  std::size_t returned = 0;  ///< Closures that kept return probes brought back to stay.
};

/// Runs at most `budget` probes from the kept set's solution (`rejected`, `poses`). `solve`
/// solves the kept set without the given rejected set (ascending) and returns where it ended;
/// `keep` is called right after a solve whose TLS cost fell, to adopt it. `cut_clusters`: false
/// = return probes only. `return_ratio`: RobustOptions::probe_return_ratio (<= 1: no return
/// probes).
ClusterProbeCounts search_cluster_probes(
    const PoseGraph& graph, const std::vector<bool>& known, double c2, int budget,
    bool cut_clusters, const ClosureClusterOptions& clusters, double return_ratio,
    std::vector<std::size_t> rejected, std::vector<Pose> poses,
    const std::function<ClusterProbeTrial(std::vector<std::size_t>)>& solve,
    const std::function<void()>& keep);

}  // namespace tessera
