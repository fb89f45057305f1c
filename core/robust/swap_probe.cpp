#include "robust/swap_probe.hpp"

#include <algorithm>
#include <cstddef>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tuple>
#include <utility>

#include "robust/probe_outcome.hpp"

namespace tessera {
namespace {

std::size_t gap(std::size_t a, std::size_t b) {
  return a > b ? a - b : b - a;
}

// An end of `a` within `near` pose ids of an end of `b`.
bool ends_meet(const Measurement& a, const Measurement& b, std::size_t near) {
  return gap(a.i, b.i) <= near || gap(a.i, b.j) <= near || gap(a.j, b.i) <= near ||
         gap(a.j, b.j) <= near;
}

}  // namespace

std::vector<ClosureSwap> swap_candidates(const PoseGraph& graph, const std::vector<bool>& known,
                                         const std::vector<Pose>& poses, double c2,
                                         const SwapRules& rules,
                                         const std::vector<std::size_t>& rejected) {
  auto r2_of = [&](std::size_t e) {
    const Measurement& m = graph.measurements[e];
    return residual_squared(m, poses[m.i], poses[m.j]);
  };
  std::vector<std::pair<double, std::size_t>> strained, back;  // (r^2, id)
  std::vector<double> kept;
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    if (known[e]) continue;
    const double r2 = r2_of(e);
    if (std::binary_search(rejected.begin(), rejected.end(), e)) {
      if (r2 <= rules.return_ratio * c2) back.emplace_back(r2, e);
      continue;
    }
    kept.push_back(r2);
    if (r2 >= rules.kept_ratio * c2) strained.emplace_back(r2, e);
  }
  std::sort(strained.begin(), strained.end(), [](const auto& x, const auto& y) {
    return x.first > y.first || (x.first == y.first && x.second < y.second);
  });
  std::sort(back.begin(), back.end());
  const std::size_t near = static_cast<std::size_t>(std::max(rules.near, 0));
  std::vector<ClosureSwap> out, alone;
  double median = 0;
  if (!kept.empty()) {
    const auto mid = kept.begin() + static_cast<std::ptrdiff_t>(kept.size() / 2);
    std::nth_element(kept.begin(), mid, kept.end());
    median = *mid;
  }
  for (const auto& [r2a, a] : strained) {
    bool paired = false;
    for (const auto& [r2b, b] : back)
      if (ends_meet(graph.measurements[a], graph.measurements[b], near)) {
        out.push_back({a, b});
        paired = true;
      }
    if (!paired && rules.alone_ratio > 0 && r2a >= rules.alone_ratio * median)
      alone.push_back({a, std::nullopt});
  }
  out.insert(out.end(), alone.begin(), alone.end());
  return out;
}

SwapProbeCounts search_swap_probes(
    const PoseGraph& graph, const std::vector<bool>& known, double c2, const SwapRules& rules,
    std::vector<std::size_t> rejected, std::vector<Pose> poses,
    const std::function<ClusterProbeTrial(std::vector<std::size_t>)>& solve,
    const std::function<void()>& keep) {
  SwapProbeCounts out;
  double best = tls_cost(graph, known, poses, c2);
  std::vector<std::pair<std::size_t, std::optional<std::size_t>>> tried;
  while (out.probes < rules.budget) {
    const std::vector<ClosureSwap> swaps =
        swap_candidates(graph, known, poses, c2, rules, rejected);
    auto fresh = std::find_if(swaps.begin(), swaps.end(), [&](const ClosureSwap& s) {
      return std::find(tried.begin(), tried.end(), std::make_pair(s.cut, s.back)) == tried.end();
    });
    if (fresh == swaps.end()) break;
    tried.emplace_back(fresh->cut, fresh->back);
    std::vector<std::size_t> next;
    next.reserve(rejected.size());
    for (std::size_t e : rejected)
      if (!fresh->back || e != *fresh->back) next.push_back(e);
    next.insert(std::upper_bound(next.begin(), next.end(), fresh->cut), fresh->cut);
    ++out.probes;
    ClusterProbeTrial t = solve(std::move(next));
    const double cost = tls_cost(graph, known, t.poses, c2);
    // The same accuracy margin as the other centralized probes (cluster_probes.cpp).
    if (probe_outcome(rejected, best, t.rejected, cost, 1e-6) != ProbeOutcome::kKept) continue;
    best = cost;
    ++out.kept;
    rejected = std::move(t.rejected);
    poses = std::move(t.poses);
    keep();
  }
  return out;
}

}  // namespace tessera
