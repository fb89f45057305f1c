#include "distributed/rounds_tail.hpp"

#include <algorithm>
#include <cmath>

namespace tessera {

double rounds_tail_gap(const std::vector<RoundRecord>& trace, int window, double max_rate) {
  if (trace.size() < 2) return 0.0;  // no round ran: the start met the tolerance
  const std::size_t w = static_cast<std::size_t>(std::max(window, 1));
  const std::size_t k = trace.size() - 1;
  const double f = trace[k].cost;
  const double scale = std::max(1.0, std::abs(f));
  if (trace.size() < 2 * w + 1) {
    // Too short for two windows: the decrease of its last half, at the capped rate (a rate
    // read from so few rounds is not trusted).
    const std::size_t h = std::max<std::size_t>(1, k / 2);
    const double d = trace[k - h].cost - f;
    return d > 0 ? d * max_rate / (1.0 - max_rate) / scale : 0.0;
  }
  const double d1 = trace[k - w].cost - f;
  const double d0 = trace[k - 2 * w].cost - trace[k - w].cost;
  if (!(d1 > 0)) return 0.0;
  const double q = d0 > 0 ? std::min(d1 / d0, max_rate) : max_rate;
  return d1 * q / (1.0 - q) / scale;
}

}  // namespace tessera
