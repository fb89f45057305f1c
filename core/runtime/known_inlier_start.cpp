#include "runtime/known_inlier_start.hpp"

#include <tessera/graph/connectivity.hpp>
#include <tessera/robust/tls_weights.hpp>

namespace tessera::agent {

std::optional<KnownInlierStart> known_inlier_start(
    const RobotShare& share, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    KnownInliers rule, const std::vector<bool>& flags) {
  auto flagged = [&](std::uint64_t e) { return e < flags.size() && flags[e]; };
  KnownInlierStart out;
  PoseGraph known;  // endpoints only: for the connectivity test
  known.d = share.d;
  known.num_poses = share.num_poses;
  for (std::size_t e = 0; e < structure.size(); ++e) {
    const auto [i, j] = structure[e];
    Measurement m;
    m.i = i;
    m.j = j;
    if (!is_known_inlier(m, rule) && !flagged(e)) continue;
    out.structure.emplace_back(i, j);
    known.measurements.push_back(std::move(m));
  }
  if (count_components(known) > 1) return std::nullopt;
  out.share.d = share.d;
  out.share.num_poses = share.num_poses;
  out.share.begin = share.begin;
  out.share.end = share.end;
  out.share.initial = share.initial;
  for (std::size_t k = 0; k < share.measurements.size(); ++k)
    if (is_known_inlier(share.measurements[k], rule) || flagged(share.measurement_index[k])) {
      out.share.measurements.push_back(share.measurements[k]);
      out.share.measurement_index.push_back(share.measurement_index[k]);
    }
  return out;
}

}  // namespace tessera::agent
