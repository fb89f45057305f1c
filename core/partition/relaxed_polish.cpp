#include "partition/relaxed_polish.hpp"

#include <cmath>
#include <string>
#include <tessera/util/input_error.hpp>

namespace tessera::partition_detail {

void RelaxedPolishOptions::validate() const {
  auto bad = [](const std::string& field, double value, const std::string& rule) {
    throw InputError("RelaxedPolishOptions." + field + " = " + std::to_string(value) + ": " + rule);
  };
  if (rounds < 0) bad("rounds", rounds, "must be >= 0");
  if (!std::isfinite(min_relax) || min_relax <= 0.0 || min_relax > 0.5)
    bad("min_relax", min_relax, "must be in (0, 0.5]");
  if (!std::isfinite(max_relax) || max_relax < min_relax || max_relax > 0.5)
    bad("max_relax", max_relax, "must be in [min_relax, 0.5]");
}

long long relaxed_polish(const WorkGraph& g, int k, const std::vector<long long>& ub,
                         std::vector<int>& part, const RelaxedPolishOptions& options,
                         const CycleParams& cycle, Rng& rng) {
  options.validate();
  long long best = edge_cut(g, part);
  for (int round = 0; round < options.rounds; ++round) {
    const double relax =
        options.min_relax + (options.max_relax - options.min_relax) * rng.uniform();
    std::vector<long long> loose = ub;
    for (long long& b : loose)
      b += std::max(1LL, static_cast<long long>(std::llround(relax * static_cast<double>(b))));
    FlowParams flow = cycle.flow;
    if (rng.next() & 1) flow.alpha *= 2;
    std::vector<int> p = part;
    kway_fm(g, k, p, loose, cycle.fm, rng);
    if (cycle.use_flow) {
      flow_refine(g, k, p, loose, flow, rng);
      kway_fm(g, k, p, loose, cycle.fm, rng);
    }
    if (!rebalance(g, k, p, ub)) continue;  // cannot happen with unit weights
    long long cut = kway_fm(g, k, p, ub, cycle.fm, rng);
    if (cycle.use_flow) {
      flow_refine(g, k, p, ub, flow, rng);
      cut = kway_fm(g, k, p, ub, cycle.fm, rng);
    }
    if (cut <= best) {
      best = cut;
      part.swap(p);
    }
  }
  return best;
}

}  // namespace tessera::partition_detail
