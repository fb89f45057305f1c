#pragma once
// Swap probes of the centralized robust solve (RobustOptions::swap_probes): after the other
// probes, a kept closure and a rejected one beside it trade places. A wrong closure can bend
// the map around one of its ends until it fits within the bound, and the true closure that
// meets it there then lies beyond the bound and is cut; each alone is judged right at that bent
// solution, so no one-at-a-time verdict undoes it, and a return probe (which keeps the wrong one
// in) cannot either: the true closure does not fit while the wrong one holds the bend. Cutting
// the wrong one and bringing the true one back together lets the map relax. The caller solves
// the swapped set (with the re-check passes) and the result stays only when the TLS cost over
// every measurement falls (probe_outcome.hpp): each kept swap is a descent step of the TLS cost,
// a refused one changes nothing.

#include <cstddef>
#include <functional>
#include <optional>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

#include "robust/cluster_probes.hpp"

namespace tessera {

/// A swap: the kept closure it cuts and the rejected closure it brings back (none: a cut alone).
struct ClosureSwap {
  std::size_t cut = 0;
  std::optional<std::size_t> back;
};

/// Which swaps are tried (RobustOptions::swap_*).
struct SwapRules {
  int budget = 0;              ///< Most swap probes (0 = none).
  int near = 0;                ///< An end of each within this many pose ids.
  double kept_ratio = 0.25;    ///< The kept closure's r^2 is at least this times c^2.
  double return_ratio = 50.0;  ///< The rejected closure's r^2 is at most this times c^2.
  /// A strained kept closure with no rejected one beside it is cut alone when its r^2 is also at
  /// least this times the median r^2 of the kept closures that may be rejected (<= 0: never).
  double alone_ratio = 5.0;
};

/// The swaps worth a try at `poses`: pairs of a kept closure (known[e] false, not in `rejected`,
/// r^2 >= kept_ratio x c^2) and a rejected one (r^2 <= return_ratio x c^2) with an end of each
/// within `near` pose ids; most strained kept closure first (largest r^2), and for one kept
/// closure the rejected ones nearest the bound first. Then the strained kept closures with no
/// such rejected one whose r^2 is at least alone_ratio x the kept median, cut alone (a wrong
/// closure bent to fit where no true closure was cut), largest r^2 first. Known measurements
/// never take part.
std::vector<ClosureSwap> swap_candidates(const PoseGraph& graph, const std::vector<bool>& known,
                                         const std::vector<Pose>& poses, double c2,
                                         const SwapRules& rules,
                                         const std::vector<std::size_t>& rejected);

struct SwapProbeCounts {
  int probes = 0;  ///< Swaps tried.
  int kept = 0;    ///< Of those, the ones that lowered the TLS cost and stayed.
};

/// Tries up to rules.budget swaps from the kept set's solution (`rejected` ascending, `poses`),
/// in swap_candidates order, the candidates named again after a kept swap (a swap tried before
/// is not tried again). `solve` solves the kept set without the given rejected set (with the
/// re-check passes) and returns where it ended; `keep` is called right after a solve whose TLS
/// cost fell, to adopt it.
SwapProbeCounts search_swap_probes(
    const PoseGraph& graph, const std::vector<bool>& known, double c2, const SwapRules& rules,
    std::vector<std::size_t> rejected, std::vector<Pose> poses,
    const std::function<ClusterProbeTrial(std::vector<std::size_t>)>& solve,
    const std::function<void()>& keep);

}  // namespace tessera
