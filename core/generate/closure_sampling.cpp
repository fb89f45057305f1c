#include "generate/closure_sampling.hpp"

#include <algorithm>

namespace tessera {

std::vector<PosePair> sample_closures(const std::vector<PosePair>& candidates,
                                      const std::vector<std::size_t>& robot_of,
                                      const ClosureSampling& sampling, RandomStream& random) {
  std::vector<PosePair> kept;
  for (const auto& c : candidates) {
    const bool same_robot = robot_of[c.first] == robot_of[c.second];
    const double p =
        same_robot ? sampling.intra_robot_probability : sampling.inter_robot_probability;
    if (random.uniform() < p) kept.push_back(c);
  }
  if (sampling.max_closures > 0 && kept.size() > sampling.max_closures) {
    // Partial Fisher-Yates: the first max_closures entries become a uniform random subset.
    for (std::size_t k = 0; k < sampling.max_closures; ++k)
      std::swap(kept[k], kept[k + random.below(kept.size() - k)]);
    kept.resize(sampling.max_closures);
    std::sort(kept.begin(), kept.end());
  }
  return kept;
}

}  // namespace tessera
