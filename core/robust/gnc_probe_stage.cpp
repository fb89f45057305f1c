// GncProbeStage (gnc_probe_stage.hpp): which probe the distributed GNC runs next, and its
// verdict.

#include "robust/gnc_probe_stage.hpp"

#include <algorithm>
#include <utility>

#include "robust/gnc_cluster_search.hpp"

namespace tessera {

GncProbeStage::GncProbeStage(const GncAgentInput& in, const GncDistributedOptions& options,
                             const std::vector<bool>& known, bool known_connected)
    : options_(options),
      known_connected_(known_connected),
      // With cluster probes the search (gnc_cluster_search.hpp) splits the budget:
      // recheck_probes tail probes, cluster_probes cluster, pair and return probes.
      probes_(options.robust.recheck_probes + options.cluster_probes) {
  if (options.cluster_probes > 0)
    search_ = std::make_unique<GncClusterSearch>(in.structure, known, options.robust.recheck_probes,
                                                 options.cluster_probes, options.clusters);
}

GncProbeStage::~GncProbeStage() = default;

bool GncProbeStage::may_start() const {
  return probes_.may_start(known_connected_, options_.robust.readmission_passes);
}

bool GncProbeStage::may_follow() const {
  return probes_.may_follow(known_connected_, options_.robust.readmission_passes);
}

bool GncProbeStage::keeps(const std::vector<std::uint64_t>& rejected, double tls) {
  const bool kept = probes_.keeps(rejected, tls);
  if (kept && search_) search_->kept();
  return kept;
}

GncProbeBase GncProbeStage::refuse(double rise) {
  GncProbeBase base = probes_.take_base();
  // The next probe starts from the restored set and iterate, which the passes had settled.
  if (search_) search_->refused(rise, base.tls);
  return base;
}

std::optional<std::vector<std::uint64_t>> GncProbeStage::next(
    std::vector<std::uint64_t> listed, const std::vector<std::uint64_t>& rejected,
    const std::vector<std::uint64_t>& gnc_rejected, bool newton_steps) {
  if (search_) {
    // The verdict lists of the set that stays: the return band of its probes, and its tail
    // probe's flips on the same rule as without cluster probes.
    std::vector<std::uint64_t> tail = flips(listed, rejected, gnc_rejected, newton_steps);
    search_->set_list(listed, tail);
    if (!may_start()) return std::nullopt;
    return search_->next(rejected);
  }
  if (!may_start()) return std::nullopt;
  std::vector<std::uint64_t> flip = flips(std::move(listed), rejected, gnc_rejected, newton_steps);
  if (flip.empty()) return std::nullopt;
  return flip;
}

std::optional<std::vector<std::uint64_t>> GncProbeStage::next_after_refusal(
    const std::vector<std::uint64_t>& rejected) {
  if (!search_ || !may_start()) return std::nullopt;
  return search_->next(rejected);
}

std::vector<std::uint64_t> GncProbeStage::flips(std::vector<std::uint64_t> listed,
                                                const std::vector<std::uint64_t>& rejected,
                                                const std::vector<std::uint64_t>& gnc_rejected,
                                                bool newton_steps) const {
  // RobustOptions::probe_cut: from GNC's own set the tail side is cut always, never, or where
  // GNC's weighted solves were rounds.
  const ProbeCut rule = options_.robust.probe_cut;
  const bool cut_untouched =
      rule == ProbeCut::kAlways || (rule == ProbeCut::kAuto && !newton_steps);
  if (cut_untouched || rejected != gnc_rejected) return listed;
  // Every agent holds the same list and set (the verdict exchange): the same flips everywhere.
  listed.erase(std::remove_if(listed.begin(), listed.end(),
                              [&](std::uint64_t id) {
                                return !std::binary_search(rejected.begin(), rejected.end(), id);
                              }),
               listed.end());
  return listed;
}

}  // namespace tessera
