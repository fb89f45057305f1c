#include <algorithm>
#include <cstdint>
#include <string>
#include <tessera/graph/connectivity.hpp>
#include <tessera/robust/closure_clusters.hpp>
#include <tessera/util/input_error.hpp>

namespace tessera {
namespace {

struct Span {
  std::size_t lo, hi;  // the closure's ends, lo < hi (a closure may be written either way)
};

Span span_of(const Measurement& m) {
  return {std::min<std::size_t>(m.i, m.j), std::max<std::size_t>(m.i, m.j)};
}

std::size_t distance(std::size_t a, std::size_t b) {
  return a > b ? a - b : b - a;
}

// Distance from id x to the id range [first, last].
std::size_t distance_to(std::size_t x, std::size_t first, std::size_t last) {
  return x < first ? first - x : x > last ? x - last : 0;
}

}  // namespace

void ClosureClusterOptions::validate() const {
  if (window < 1)
    throw InputError("ClosureClusterOptions.window = " + std::to_string(window) + ": must be >= 1");
  if (min_size < 2)
    throw InputError("ClosureClusterOptions.min_size = " + std::to_string(min_size) +
                     ": must be >= 2");
  if (near < 0)
    throw InputError("ClosureClusterOptions.near = " + std::to_string(near) + ": must be >= 0");
}

ClusterUnion partly_cut_runs(const std::vector<ClosureCluster>& clusters) {
  ClusterUnion out;
  for (const ClosureCluster& c : clusters)
    if (c.rejected_in_run > 0) {
      out.parts.push_back(c);
      out.members.insert(out.members.end(), c.members.begin(), c.members.end());
    }
  if (out.parts.size() < 2) return {};
  std::sort(out.members.begin(), out.members.end());
  return out;
}

bool clusters_meet(const ClosureCluster& a, const ClosureCluster& b, int near) {
  // Two id ranges meet when the gap between them is at most `near`.
  auto gap = [](std::size_t f1, std::size_t l1, std::size_t f2, std::size_t l2) {
    return l1 < f2 ? f2 - l1 : l2 < f1 ? f1 - l2 : 0;
  };
  const std::size_t n = static_cast<std::size_t>(std::max(near, 0));
  return gap(a.lo_first, a.lo_last, b.lo_first, b.lo_last) <= n ||
         gap(a.lo_first, a.lo_last, b.hi_first, b.hi_last) <= n ||
         gap(a.hi_first, a.hi_last, b.lo_first, b.lo_last) <= n ||
         gap(a.hi_first, a.hi_last, b.hi_first, b.hi_last) <= n;
}

std::vector<ClosureCluster> closure_clusters(const PoseGraph& graph, const std::vector<bool>& known,
                                             const std::vector<std::size_t>& rejected,
                                             const ClosureClusterOptions& options) {
  options.validate();
  const std::size_t w = static_cast<std::size_t>(options.window);
  std::vector<std::size_t> kept;  // candidate closures still in, ordered by their lower end
  std::vector<std::size_t> cut;   // rejected closures
  for (std::size_t e = 0; e < graph.num_measurements(); ++e) {
    if (known[e]) continue;
    (std::binary_search(rejected.begin(), rejected.end(), e) ? cut : kept).push_back(e);
  }
  std::stable_sort(kept.begin(), kept.end(), [&](std::size_t a, std::size_t b) {
    return span_of(graph.measurements[a]).lo < span_of(graph.measurements[b]).lo;
  });
  // The pairs within the window (positions in `kept`): a sweep over the lower ends, so only
  // closures whose lower ends are within the window are compared. Clusters: their components.
  std::vector<std::pair<std::size_t, std::size_t>> within;
  for (std::size_t a = 0; a < kept.size(); ++a) {
    const Span sa = span_of(graph.measurements[kept[a]]);
    for (std::size_t b = a + 1; b < kept.size(); ++b) {
      const Span sb = span_of(graph.measurements[kept[b]]);
      if (sb.lo > sa.lo + w) break;
      if (distance(sa.hi, sb.hi) <= w) within.emplace_back(a, b);
    }
  }
  const std::vector<std::size_t> component = connected_components(kept.size(), within);
  std::vector<std::vector<std::size_t>> groups(kept.size());
  for (std::size_t a = 0; a < kept.size(); ++a) groups[component[a]].push_back(kept[a]);

  // The rejected closures by lower end, to find those in a cluster's own run.
  std::vector<Span> cut_spans;
  for (std::size_t e : cut) cut_spans.push_back(span_of(graph.measurements[e]));
  std::sort(cut_spans.begin(), cut_spans.end(), [](const Span& a, const Span& b) {
    return a.lo < b.lo || (a.lo == b.lo && a.hi < b.hi);
  });
  auto in_run = [&](const std::vector<std::size_t>& members) {
    std::vector<std::size_t> found;  // positions in cut_spans
    for (std::size_t e : members) {
      const Span s = span_of(graph.measurements[e]);
      auto it = std::lower_bound(cut_spans.begin(), cut_spans.end(), s.lo > w ? s.lo - w : 0,
                                 [](const Span& a, std::size_t lo) { return a.lo < lo; });
      for (; it != cut_spans.end() && it->lo <= s.lo + w; ++it)
        if (distance(it->hi, s.hi) <= w)
          found.push_back(static_cast<std::size_t>(it - cut_spans.begin()));
    }
    std::sort(found.begin(), found.end());
    return static_cast<std::size_t>(std::unique(found.begin(), found.end()) - found.begin());
  };

  std::vector<ClosureCluster> out;
  const std::size_t near = static_cast<std::size_t>(options.near);
  for (std::vector<std::size_t>& g : groups) {
    if (g.size() < options.min_size) continue;
    std::sort(g.begin(), g.end());
    std::size_t lo_first = SIZE_MAX, lo_last = 0, hi_first = SIZE_MAX, hi_last = 0;
    for (std::size_t e : g) {
      const Span s = span_of(graph.measurements[e]);
      lo_first = std::min(lo_first, s.lo);
      lo_last = std::max(lo_last, s.lo);
      hi_first = std::min(hi_first, s.hi);
      hi_last = std::max(hi_last, s.hi);
    }
    ClosureCluster c;
    c.lo_first = lo_first;
    c.lo_last = lo_last;
    c.hi_first = hi_first;
    c.hi_last = hi_last;
    for (std::size_t e : cut) {
      const Span s = span_of(graph.measurements[e]);
      const std::size_t d =
          std::min({distance_to(s.lo, lo_first, lo_last), distance_to(s.lo, hi_first, hi_last),
                    distance_to(s.hi, lo_first, lo_last), distance_to(s.hi, hi_first, hi_last)});
      if (d <= near) ++c.rejected_near;
    }
    if (c.rejected_near < options.min_rejected_near) continue;
    c.rejected_in_run = in_run(g);
    c.members = std::move(g);
    out.push_back(std::move(c));
  }
  std::sort(out.begin(), out.end(), [](const ClosureCluster& a, const ClosureCluster& b) {
    const bool a_cut = a.rejected_in_run > 0, b_cut = b.rejected_in_run > 0;
    if (a_cut != b_cut) return a_cut;
    if (a.members.size() != b.members.size()) return a.members.size() > b.members.size();
    if (a.rejected_near != b.rejected_near) return a.rejected_near > b.rejected_near;
    return a.members.front() < b.members.front();
  });
  return out;
}

}  // namespace tessera
