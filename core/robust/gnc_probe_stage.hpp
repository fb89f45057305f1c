#pragma once
// The probes of the distributed GNC after its re-check passes (RobustOptions::recheck_probes,
// GncDistributedOptions::cluster_probes): whether one may start, which measurements the next one
// flips, and whether the running one stays. GncAgent's state machine starts a probe with the
// flips this names and restores the set and iterate a refused one goes back to (GncProbeBase).
//
// Every agent holds the same verdict lists and rejected sets (the verdict exchange) and runs the
// same search on them: the same flips everywhere, with no message of its own.

#include <cstdint>
#include <memory>
#include <optional>
#include <tessera/robust/gnc_agent.hpp>
#include <vector>

#include "robust/gnc_probes.hpp"

namespace tessera {

class GncClusterSearch;

class GncProbeStage {
 public:
  /// `options` must outlive the stage. `known`: one flag per measurement of the whole graph
  /// (GncLocalTerms::known); `known_connected`: the known inliers connect the poses.
  GncProbeStage(const GncAgentInput& in, const GncDistributedOptions& options,
                const std::vector<bool>& known, bool known_connected);
  ~GncProbeStage();
  GncProbeStage(const GncProbeStage&) = delete;
  GncProbeStage& operator=(const GncProbeStage&) = delete;

  /// Another probe may start now (none running, budget left, passes to judge it).
  bool may_start() const;
  /// A probe may start once the running one ends: its verdict must list the candidates.
  bool may_follow() const;
  bool running() const { return probes_.running(); }
  /// The passes put the set back to the running probe's base: it ends, not kept.
  bool back_at_base(const std::vector<std::uint64_t>& rejected) const {
    return probes_.back_at_base(rejected);
  }
  /// A probe starts from `base` (what it goes back to when refused).
  void start(GncProbeBase base) { probes_.start(std::move(base)); }
  /// The running probe's judgement at the passes' end, with the set `rejected` and the summed
  /// TLS cost `tls`: whether it stays (otherwise refuse()).
  bool keeps(const std::vector<std::uint64_t>& rejected, double tls);
  double base_tls() const { return probes_.base_tls(); }
  /// Ends the running probe without keeping it, its TLS cost `rise` above the base's (0 when no
  /// verdict judged it): the state to restore.
  GncProbeBase refuse(double rise);
  /// The flips of the next probe from a state that stays (the first after the passes, or after
  /// a kept probe): `listed` is every agent's verdict list there, `rejected` the set (ascending),
  /// `gnc_rejected` GNC's own set, `newton_steps` whether GNC's weighted solves were all Newton
  /// steps (RobustOptions::probe_cut). nullopt: no probe.
  std::optional<std::vector<std::uint64_t>> next(std::vector<std::uint64_t> listed,
                                                 const std::vector<std::uint64_t>& rejected,
                                                 const std::vector<std::uint64_t>& gnc_rejected,
                                                 bool newton_steps);
  /// The flips of the next probe after a refused one, from the restored set `rejected` (only the
  /// cluster search goes on from there).
  std::optional<std::vector<std::uint64_t>> next_after_refusal(
      const std::vector<std::uint64_t>& rejected);

  int started() const { return probes_.started(); }
  int kept() const { return probes_.kept(); }

 private:
  // The part of a probe list the probe flips: all of it, or, while the set is still GNC's own
  // and RobustOptions::probe_cut says so, only the rejected ones (the return side).
  std::vector<std::uint64_t> flips(std::vector<std::uint64_t> listed,
                                   const std::vector<std::uint64_t>& rejected,
                                   const std::vector<std::uint64_t>& gnc_rejected,
                                   bool newton_steps) const;

  const GncDistributedOptions& options_;
  bool known_connected_;
  GncProbes probes_;                          // budget, running probe, its base, the verdicts
  std::unique_ptr<GncClusterSearch> search_;  // GncDistributedOptions::cluster_probes (> 0)
};

}  // namespace tessera
