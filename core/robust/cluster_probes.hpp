#pragma once
// The search of the centralized cluster probes (GncCentralizedOptions::cluster_probes): which
// set to try next after the re-check passes, and when to stop. A probe cuts a run of kept
// closures (closure_clusters.hpp), or several runs that share a stretch, or takes back one
// rejected closure just beyond the bound; the caller solves the kept set from there (with the
// re-check passes) and the result stays only when the TLS cost over every measurement falls.
// Every kept probe is a descent step of the TLS cost; a refused one changes nothing.

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
  int probes = 0;  ///< Probes run.
  int kept = 0;    ///< Of those, the ones that lowered the TLS cost and stayed.
};

/// Runs at most `budget` probes from the kept set's solution (`rejected`, `poses`). `solve`
/// solves the kept set without the given rejected set (ascending) and returns where it ended;
/// `keep` is called right after a solve whose TLS cost fell, to adopt it. `readmit_ratio`: see
/// GncCentralizedOptions (0 = no readmission probes).
ClusterProbeCounts search_cluster_probes(
    const PoseGraph& graph, const std::vector<bool>& known, double c2, int budget,
    const ClosureClusterOptions& clusters, double readmit_ratio, std::vector<std::size_t> rejected,
    std::vector<Pose> poses,
    const std::function<ClusterProbeTrial(std::vector<std::size_t>)>& solve,
    const std::function<void()>& keep);

}  // namespace tessera
