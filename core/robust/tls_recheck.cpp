#include <algorithm>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>

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
