#pragma once
// The search of the centralized probes after the re-check passes (GncCentralizedOptions::
// cluster_probes, RobustOptions::probe_return_ratio): which set to try next, and when to stop.
// A probe cuts the kept closures far above the median residual while the rejected ones just
// beyond the bound come back (a tail probe), or cuts a run of kept closures (closure_clusters.hpp),
// or several runs that share a stretch (first every run GNC partly cut, together), or takes back
// rejected closures just beyond the bound
// (all of them together, then one at a time; together first right after a kept probe, whose cut
// may have let true closures back within reach); the caller solves the kept set from there (with
// the re-check passes) and the result stays only when the TLS cost over every measurement falls.
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
  int probes = 0;            ///< Probes run.
  int kept = 0;              ///< Of those, the ones that lowered the TLS cost and stayed.
  std::size_t returned = 0;  ///< Closures that kept return probes brought back to stay.
};

/// Which probes the search may run.
struct ProbeRules {
  int budget = 0;             ///< Most cluster and return probes.
  bool cut_clusters = false;  ///< false = no cluster probes (return and tail probes only).
  ClosureClusterOptions clusters;
  /// RobustOptions::probe_return_ratio (<= 1: no return probes).
  double return_ratio = 1.0;
  /// Most tail probes, besides the budget (RobustOptions::recheck_probes; 0 = none): the kept
  /// closures far above the median residual leave together while the return band comes back
  /// (tls_recheck.hpp, tail_candidates), as the distributed probe does.
  int tail_probes = 0;
  double tail_cut_ratio = 5.0;  ///< RobustOptions::probe_ratio.
  double tail_ratio = 1.5;      ///< RobustOptions::probe_tail_ratio.
};

/// Runs the probes `rules` allows from the kept set's solution (`rejected`, `poses`): first a
/// tail probe when the kept residuals have a heavy tail, then cluster probes, then return
/// probes; after a kept probe every kind may run again. `solve` solves the kept set without the
/// given rejected set (ascending) and returns where it ended; `keep` is called right after a
/// solve whose TLS cost fell, to adopt it.
ClusterProbeCounts search_cluster_probes(
    const PoseGraph& graph, const std::vector<bool>& known, double c2, const ProbeRules& rules,
    std::vector<std::size_t> rejected, std::vector<Pose> poses,
    const std::function<ClusterProbeTrial(std::vector<std::size_t>)>& solve,
    const std::function<void()>& keep);

}  // namespace tessera
