#include "partition/light_block.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace tessera::partition_detail {

std::vector<long long> light_block_bounds(const std::vector<long long>& ub, long long total,
                                          int block, double fraction) {
  std::vector<long long> out = ub;
  const int k = static_cast<int>(ub.size());
  const long long others = std::accumulate(ub.begin(), ub.end(), 0LL) - ub[block];
  const double avg = static_cast<double>(total) / k;
  const long long margin = std::max(1LL, static_cast<long long>(0.01 * avg));
  const long long wanted = static_cast<long long>(std::floor(fraction * avg));
  out[block] = std::min(ub[block], std::max(wanted, total - others + margin));
  return out;
}

std::vector<long long> random_light_bounds(const WorkGraph& g, const std::vector<int>& part,
                                           const std::vector<long long>& ub, double min_fraction,
                                           double max_fraction, Rng& rng) {
  const int k = static_cast<int>(ub.size());
  int block = rng.below(k);
  if (rng.next() & 1) {
    const std::vector<long long> bw = block_weights(g, part, k);
    block = static_cast<int>(std::min_element(bw.begin(), bw.end()) - bw.begin());
  }
  const double fraction = min_fraction + (max_fraction - min_fraction) * rng.uniform();
  return light_block_bounds(ub, g.total_vw, block, fraction);
}

}  // namespace tessera::partition_detail
