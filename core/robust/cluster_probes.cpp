#include "robust/cluster_probes.hpp"

#include <algorithm>
#include <iterator>
#include <tessera/robust/tls_recheck.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <utility>

namespace tessera {
namespace {

// A probe: the clusters it cuts together, and their members (ascending).
struct Probe {
  std::vector<ClosureCluster> parts;
  std::vector<std::size_t> members;
};

}  // namespace

ClusterProbeCounts search_cluster_probes(
    const PoseGraph& graph, const std::vector<bool>& known, double c2, int budget,
    const ClosureClusterOptions& clusters, double readmit_ratio, std::vector<std::size_t> rejected,
    std::vector<Pose> poses,
    const std::function<ClusterProbeTrial(std::vector<std::size_t>)>& solve,
    const std::function<void()>& keep) {
  ClusterProbeCounts out;
  double best = tls_cost(graph, known, poses, c2);
  // Probes tried since the set last changed, and those among them whose cut raised the TLS cost
  // (with the rise): two runs that share a stretch can hold one bend together, so that cutting
  // either alone costs more and cutting both costs less (intel, group 0.5: TLS 4821 -> 4893 and
  // 4857 alone). When no single cluster is left, each of those (smallest rise first) is tried
  // together with a cluster that shares a stretch with it: the single ones that raised the cost
  // first, then any cluster, also one that no cut closure points at.
  std::vector<std::vector<std::size_t>> tried;
  std::vector<std::pair<double, Probe>> raised;
  std::vector<std::size_t> readmit_tried;  // rejected closures taken back alone since then
  auto untried = [&](const std::vector<std::size_t>& p) {
    return std::find(tried.begin(), tried.end(), p) == tried.end();
  };
  ClosureClusterOptions every = clusters;
  every.min_rejected_near = 0;
  // Runs `next` (the rejected set to try); adopts it when the TLS cost fell by more than the
  // solves' accuracy (the same set solved again ends within it).
  auto attempt = [&](std::vector<std::size_t> next) {
    ++out.probes;
    ClusterProbeTrial t = solve(std::move(next));
    const double cost = tls_cost(graph, known, t.poses, c2);
    if (!(cost < best * (1 - 1e-6))) return cost - best;
    best = cost;
    ++out.kept;
    rejected = std::move(t.rejected);
    poses = std::move(t.poses);
    tried.clear();  // with the set changed, a probe refused before may now lower the cost
    raised.clear();
    readmit_tried.clear();
    keep();
    return 0.0;
  };
  while (out.probes < budget) {
    Probe probe;
    for (const ClosureCluster& c : closure_clusters(graph, known, rejected, clusters))
      if (untried(c.members)) {
        probe.parts = {c};
        probe.members = c.members;
        break;
      }
    if (probe.members.empty() && !raised.empty()) {
      std::stable_sort(raised.begin(), raised.end(),
                       [](const auto& x, const auto& y) { return x.first < y.first; });
      std::vector<ClosureCluster> partners;
      for (const auto& r : raised)
        if (r.second.parts.size() == 1) partners.push_back(r.second.parts.front());
      for (ClosureCluster& c : closure_clusters(graph, known, rejected, every))
        partners.push_back(std::move(c));
      for (std::size_t x = 0; x < raised.size() && probe.members.empty(); ++x)
        for (std::size_t y = 0; y < partners.size() && probe.members.empty(); ++y) {
          const Probe& a = raised[x].second;
          const ClosureCluster& b = partners[y];
          bool inside = false, meets = false;
          for (const ClosureCluster& part : a.parts) {
            inside = inside || part.members == b.members;
            meets = meets || clusters_meet(part, b, clusters.near);
          }
          if (inside || !meets) continue;
          std::vector<std::size_t> both;
          std::set_union(a.members.begin(), a.members.end(), b.members.begin(), b.members.end(),
                         std::back_inserter(both));
          if (!untried(both)) continue;
          probe.parts = a.parts;
          probe.parts.push_back(b);
          probe.members = std::move(both);
        }
    }
    if (!probe.members.empty()) {
      tried.push_back(probe.members);
      std::vector<std::size_t> next = rejected;
      next.insert(next.end(), probe.members.begin(), probe.members.end());
      std::sort(next.begin(), next.end());
      const double rise = attempt(std::move(next));
      if (rise > 1e-6 * best) raised.emplace_back(rise, std::move(probe));
      continue;
    }
    // Last, a rejected closure just beyond the bound (r^2 <= readmit_ratio c^2 at the kept set's
    // solution), nearest first, taken back alone: a true closure that a cut run's bend pushed out
    // can stay beyond the bound at a local solution that fitting it would move (intel, group 0.1:
    // r^2 71.9 against c^2 = 32.8, 4.3 at the clean optimum).
    std::size_t readmit = graph.num_measurements();
    double readmit_r2 = 0;
    if (readmit_ratio > 0)
      for (std::size_t e : rejected) {
        const Measurement& m = graph.measurements[e];
        const double r2 = residual_squared(m, poses[m.i], poses[m.j]);
        if (known[e] || r2 > readmit_ratio * c2 ||
            std::find(readmit_tried.begin(), readmit_tried.end(), e) != readmit_tried.end())
          continue;
        if (readmit == graph.num_measurements() || r2 < readmit_r2) {
          readmit = e;
          readmit_r2 = r2;
        }
      }
    if (readmit == graph.num_measurements()) break;
    readmit_tried.push_back(readmit);
    std::vector<std::size_t> next;
    for (std::size_t e : rejected)
      if (e != readmit) next.push_back(e);
    attempt(std::move(next));
  }
  return out;
}

}  // namespace tessera
