#pragma once
// Probes after the distributed re-check passes (RobustOptions::recheck_probes): how many may
// run, the kept set and iterate a running probe started from, and the rule that keeps it.
// GncAgent decides when a probe starts and what it cuts; this holds what a probe that fails
// goes back to, so the state machine does not carry a second copy of its own fields.

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "robust/probe_outcome.hpp"

namespace tessera {

/// What a probe goes back to when it does not lower the TLS cost.
struct GncProbeBase {
  double tls = 0;  ///< Summed TLS cost before the probe.
  std::vector<std::uint64_t> rejected;
  std::vector<double> weights;
  Eigen::MatrixXd Y;
  std::size_t readmitted = 0, late_rejected = 0;
};

class GncProbes {
 public:
  explicit GncProbes(int allowed) : allowed_(allowed) {}

  /// Another probe may start: none running, fewer than `allowed` so far, and the known inliers
  /// connect the poses (a probe cuts many closures at once) with re-check passes to judge it.
  bool may_start(bool known_connected, int readmission_passes) const {
    return !running_ && started_ < allowed_ && known_connected && readmission_passes > 0;
  }
  /// A probe may start once the running one (if any) ends: the same as may_start but for the
  /// running probe. The verdict that ends a kept probe must already name the next probe's
  /// candidates, or a budget of two probes would never start its second after a kept first.
  bool may_follow(bool known_connected, int readmission_passes) const {
    return started_ < allowed_ && known_connected && readmission_passes > 0;
  }
  void start(GncProbeBase base) {
    ++started_;
    running_ = true;
    base_ = std::move(base);
  }
  bool running() const { return running_; }
  /// Ends the running probe's judgement at the passes' end, with the set `rejected` (ascending)
  /// and the summed TLS cost `tls`: it stays (and counts as kept) only if the set is not the
  /// base's and the cost fell below the base's beyond the solves' own accuracy
  /// (probe_outcome.hpp).
  bool keeps(const std::vector<std::uint64_t>& rejected, double tls) {
    running_ = false;
    const bool kept =
        probe_outcome(base_.rejected, base_.tls, rejected, tls, 1e-9) == ProbeOutcome::kKept;
    if (kept) ++kept_;
    return kept;
  }
  /// A pass's verdict put the set back to the running probe's base (what it cut came back): the
  /// probe ends there, not kept (probe_outcome.hpp), without solving that set again.
  bool back_at_base(const std::vector<std::uint64_t>& rejected) const {
    return running_ && rejected == base_.rejected;
  }
  /// Ends the running probe without keeping it; the state to restore.
  GncProbeBase take_base() {
    running_ = false;
    return std::move(base_);
  }
  /// The summed TLS cost before the running probe.
  double base_tls() const { return base_.tls; }
  /// The rejected set the running probe started from (ascending).
  const std::vector<std::uint64_t>& base_rejected() const { return base_.rejected; }
  int started() const { return started_; }
  int kept() const { return kept_; }

 private:
  int allowed_ = 0;
  bool running_ = false;
  int started_ = 0, kept_ = 0;
  GncProbeBase base_;
};

}  // namespace tessera
