#include "distributed/rounds_tail.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tessera {

double rounds_tail_gap(const std::vector<RoundRecord>& trace, int window, double max_rate) {
  const std::size_t w = static_cast<std::size_t>(std::max(window, 1));
  if (trace.size() < 2 * w + 1) return std::numeric_limits<double>::infinity();
  const std::size_t k = trace.size() - 1;
  const double f = trace[k].cost;
  const double d1 = trace[k - w].cost - f;
  const double d0 = trace[k - 2 * w].cost - trace[k - w].cost;
  if (!(d1 > 0)) return 0.0;
  const double q = d0 > 0 ? std::min(d1 / d0, max_rate) : max_rate;
  return d1 * q / (1.0 - q) / std::max(1.0, std::abs(f));
}

}  // namespace tessera
