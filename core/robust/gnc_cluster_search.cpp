#include "robust/gnc_cluster_search.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

namespace tessera {

GncClusterSearch::GncClusterSearch(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure, std::vector<bool> known,
    int tail_budget, int budget, ClosureClusterOptions clusters)
    : known_(std::move(known)),
      tail_budget_(tail_budget),
      budget_(budget),
      clusters_(std::move(clusters)) {
  if (known_.size() != structure.size())
    throw std::invalid_argument("GncClusterSearch: one known-inlier flag per measurement expected");
  clusters_.validate();
  skeleton_.measurements.reserve(structure.size());
  for (const auto& [i, j] : structure) {
    Measurement m;
    m.i = i;
    m.j = j;
    skeleton_.measurements.push_back(std::move(m));
    skeleton_.num_poses = std::max<std::size_t>(skeleton_.num_poses, std::max(i, j) + 1);
  }
}

namespace {
std::vector<std::uint64_t> sorted_unique(std::vector<std::uint64_t> ids) {
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}
}  // namespace

void GncClusterSearch::set_list(const std::vector<std::uint64_t>& listed,
                                const std::vector<std::uint64_t>& tail) {
  listed_ = sorted_unique(listed);
  tail_ = sorted_unique(tail);
}

bool GncClusterSearch::untried(const std::vector<std::size_t>& members) const {
  return std::find(tried_.begin(), tried_.end(), members) == tried_.end();
}

std::optional<GncClusterSearch::Probe> GncClusterSearch::next_cluster(
    const std::vector<std::uint64_t>& rejected) const {
  const std::vector<std::size_t> cut(rejected.begin(), rejected.end());
  const std::vector<ClosureCluster> listed = closure_clusters(skeleton_, known_, cut, clusters_);
  // First every run GNC partly cut, together (partly_cut_runs).
  Probe partly = partly_cut_runs(listed);
  if (!partly.members.empty() && untried(partly.members)) return partly;
  // One cluster that was not tried since the set last changed, in closure_clusters' order.
  for (const ClosureCluster& c : listed)
    if (untried(c.members)) return Probe{{c}, c.members};
  if (raised_.empty()) return std::nullopt;
  // Two runs that share a stretch can hold one bend together, so that cutting either alone
  // raises the TLS cost and cutting both lowers it (the centralized search's rule,
  // cluster_probes.cpp): each cut that raised the cost (smallest rise first) with a cluster that
  // shares a stretch with it, the single ones that raised the cost first, then any cluster.
  std::vector<std::pair<double, Probe>> raised = raised_;
  std::stable_sort(raised.begin(), raised.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<ClosureCluster> partners;
  for (const auto& r : raised)
    if (r.second.parts.size() == 1) partners.push_back(r.second.parts.front());
  ClosureClusterOptions every = clusters_;
  every.min_rejected_near = 0;
  for (ClosureCluster& c : closure_clusters(skeleton_, known_, cut, every))
    partners.push_back(std::move(c));
  for (const auto& r : raised)
    for (const ClosureCluster& b : partners) {
      const Probe& a = r.second;
      bool inside = false, meets = false;
      for (const ClosureCluster& part : a.parts) {
        inside = inside || part.members == b.members;
        meets = meets || clusters_meet(part, b, clusters_.near);
      }
      if (inside || !meets) continue;
      std::vector<std::size_t> both;
      std::set_union(a.members.begin(), a.members.end(), b.members.begin(), b.members.end(),
                     std::back_inserter(both));
      if (!untried(both)) continue;
      Probe p{a.parts, std::move(both)};
      p.parts.push_back(b);
      return p;
    }
  return std::nullopt;
}

std::optional<std::vector<std::uint64_t>> GncClusterSearch::next(
    const std::vector<std::uint64_t>& rejected) {
  running_.reset();
  auto is_rejected = [&](std::uint64_t id) {
    return std::binary_search(rejected.begin(), rejected.end(), id);
  };
  std::vector<std::uint64_t> band;
  std::copy_if(listed_.begin(), listed_.end(), std::back_inserter(band), is_rejected);
  // First, the agents' tail probe: the kept measurements they named leave, the band comes back.
  if (tail_used_ < tail_budget_ && !tail_tried_) {
    tail_tried_ = true;
    if (!tail_.empty()) {
      ++tail_used_;
      // A tail probe that only returns the band is the band-together probe: not tried twice.
      if (tail_ == band) {
        returned_together_ = true;
        if (band.size() == 1) returned_alone_.push_back(band.front());
      }
      return tail_;
    }
  }
  if (used_ >= budget_) return std::nullopt;
  // Right after a kept probe, the band together first: the true closures a cut fold had pushed
  // beyond the bound come back there, before another cluster is cut on their account.
  if (band_first_ && !band.empty()) {
    band_first_ = false;
    returned_together_ = true;
    if (band.size() == 1) returned_alone_.push_back(band.front());
    ++used_;
    return band;
  }
  band_first_ = false;
  if (std::optional<Probe> p = next_cluster(rejected)) {
    ++used_;
    tried_.push_back(p->members);
    running_ = std::move(p);
    return std::vector<std::uint64_t>(running_->members.begin(), running_->members.end());
  }
  // Last, the return band (rejected closures within RobustOptions::probe_return_ratio c^2 at the
  // state's solution): all together, then one at a time in file order.
  std::vector<std::uint64_t> back;
  if (band.size() > 1 && !returned_together_) {
    returned_together_ = true;
    back = band;
  } else {
    for (std::uint64_t e : band)
      if (std::find(returned_alone_.begin(), returned_alone_.end(), e) == returned_alone_.end()) {
        back = {e};
        returned_alone_.push_back(e);
        break;
      }
  }
  if (back.empty()) return std::nullopt;
  ++used_;
  return back;
}

void GncClusterSearch::kept() {
  running_.reset();
  tried_.clear();
  raised_.clear();
  returned_together_ = false;
  returned_alone_.clear();
  tail_tried_ = false;
  band_first_ = true;
}

void GncClusterSearch::refused(double rise, double base) {
  if (running_ && rise > 1e-6 * std::abs(base)) raised_.emplace_back(rise, std::move(*running_));
  running_.reset();
}

}  // namespace tessera
