#pragma once
// TLS's own verdict on a set of kept measurements at given poses: the step after GNC that
// judges every rejectable measurement at the inlier set's solution (RobustOptions::
// readmission_passes). With the poses fixed, the binary weights that minimise the TLS cost
// sum_e min(r_e^2, c^2) are w_e = [r_e^2 <= c^2]; alternating this with a solve of the kept set
// never raises the TLS cost.

#include <cstddef>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

struct TlsRecheck {
  std::vector<std::size_t> rejected;  ///< Measurements with r^2 > c^2 (not known), ascending.
  std::size_t taken_back = 0;         ///< Rejected before, within the bound now.
  std::size_t dropped = 0;            ///< Kept before, beyond the bound now.
};

/// The verdict at `poses` for every measurement with known[e] false (known ones are never
/// rejected), compared with the previous `rejected` set (ascending).
TlsRecheck tls_recheck(const PoseGraph& graph, const std::vector<bool>& known,
                       const std::vector<Pose>& poses, double c2,
                       const std::vector<std::size_t>& rejected);

/// What a return probe takes back (RobustOptions::probe_return_ratio): the rejected measurements
/// (`rejected` ascending, known ones never in it) whose r^2 at `poses` lies beyond the bound but
/// within return_ratio x c^2, nearest to the bound first. The same band the distributed probe's
/// verdict names (gnc_votes). Empty when return_ratio <= 1.
std::vector<std::size_t> return_candidates(const PoseGraph& graph, const std::vector<Pose>& poses,
                                           double c2, double return_ratio,
                                           const std::vector<std::size_t>& rejected);

/// What a tail probe cuts (RobustOptions::probe_ratio, probe_tail_ratio; the centralized form of
/// the distributed probe's list, gnc_votes): the kept measurements that may be rejected (known[e]
/// false, not in `rejected`, ascending) whose r^2 at `poses` is within the bound but above
/// cut_ratio x the median r^2 of those kept ones, when their mean r^2 is above tail_ratio x that
/// median (a heavy tail: a map bent until some wrong closures fit); otherwise none. Ascending.
std::vector<std::size_t> tail_candidates(const PoseGraph& graph, const std::vector<bool>& known,
                                         const std::vector<Pose>& poses, double c2,
                                         double cut_ratio, double tail_ratio,
                                         const std::vector<std::size_t>& rejected);

/// The TLS cost at `poses`: sum over the measurements of r^2 for known ones (known[e] true, never
/// rejected) and min(r^2, c^2) for the others. What the start vote, the re-check passes and the
/// cluster probes compare.
double tls_cost(const PoseGraph& graph, const std::vector<bool>& known,
                const std::vector<Pose>& poses, double c2);

}  // namespace tessera
