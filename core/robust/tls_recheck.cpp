#include <algorithm>
#include <cstddef>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <utility>

namespace tessera {

TlsRecheck tls_recheck(const PoseGraph& graph, const std::vector<bool>& known,
                       const std::vector<Pose>& poses, double c2,
                       const std::vector<std::size_t>& rejected) {
  TlsRecheck out;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    if (known[e]) continue;
    const Measurement& m = graph.measurements[e];
    const bool was_rejected = std::binary_search(rejected.begin(), rejected.end(), e);
    const bool fits = residual_squared(m, poses[m.i], poses[m.j]) <= c2;
    if (!fits) out.rejected.push_back(e);
    if (was_rejected && fits) ++out.taken_back;
    if (!was_rejected && !fits) ++out.dropped;
  }
  return out;
}

std::vector<std::size_t> return_candidates(const PoseGraph& graph, const std::vector<Pose>& poses,
                                           double c2, double return_ratio,
                                           const std::vector<std::size_t>& rejected) {
  std::vector<std::pair<double, std::size_t>> band;
  for (std::size_t e : rejected) {
    const Measurement& m = graph.measurements[e];
    const double r2 = residual_squared(m, poses[m.i], poses[m.j]);
    if (r2 > c2 && r2 <= return_ratio * c2) band.emplace_back(r2, e);
  }
  std::sort(band.begin(), band.end());
  std::vector<std::size_t> out;
  out.reserve(band.size());
  for (const auto& b : band) out.push_back(b.second);
  return out;
}

std::vector<std::size_t> tail_candidates(const PoseGraph& graph, const std::vector<bool>& known,
                                         const std::vector<Pose>& poses, double c2,
                                         double cut_ratio, double tail_ratio,
                                         const std::vector<std::size_t>& rejected) {
  std::vector<std::pair<double, std::size_t>> kept;  // (r^2, id) of the kept ones that fit
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    if (known[e] || std::binary_search(rejected.begin(), rejected.end(), e)) continue;
    const Measurement& m = graph.measurements[e];
    const double r2 = residual_squared(m, poses[m.i], poses[m.j]);
    if (r2 <= c2) kept.emplace_back(r2, e);
  }
  std::vector<std::size_t> out;
  if (kept.empty()) return out;
  std::vector<double> r2s;
  r2s.reserve(kept.size());
  double sum = 0;
  for (const auto& k : kept) {
    r2s.push_back(k.first);
    sum += k.first;
  }
  const auto mid = r2s.begin() + static_cast<std::ptrdiff_t>(r2s.size() / 2);
  std::nth_element(r2s.begin(), mid, r2s.end());
  // Without a heavy tail (mean near the median, as for residuals that match their information)
  // there is no bend for a probe to undo.
  if (!(sum > tail_ratio * *mid * static_cast<double>(r2s.size()))) return out;
  for (const auto& [r2, e] : kept)
    if (r2 > cut_ratio * *mid) out.push_back(e);
  return out;
}

double tls_cost(const PoseGraph& graph, const std::vector<bool>& known,
                const std::vector<Pose>& poses, double c2) {
  double f = 0;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    const Measurement& m = graph.measurements[e];
    const double r2 = residual_squared(m, poses[m.i], poses[m.j]);
    f += known[e] ? r2 : std::min(r2, c2);
  }
  return f;
}

}  // namespace tessera
