// GncAgent's side of the probes: a probe starts from the current set and iterate (its flips
// named by GncProbeStage), and a refused one restores them. The state machine that decides when
// to probe is gnc_agent.cpp.

#include <optional>
#include <tessera/robust/gnc_agent.hpp>
#include <utility>
#include <vector>

#include "robust/gnc_inlier_passes.hpp"
#include "robust/gnc_kept_start_votes.hpp"
#include "robust/gnc_probe_stage.hpp"
#include "robust/gnc_solve_stage.hpp"
#include "robust/gnc_votes.hpp"

namespace tessera {

void GncAgent::begin_probe(double tls, std::vector<std::uint64_t> flip,
                           std::vector<OutgoingMessage>& out) {
  // Every agent holds every agent's probe list (the verdict exchange) and runs the same cluster
  // search: the same flips everywhere.
  probes_->start(
      GncProbeBase{tls, rejected_, weights_, stage_->iterate(), readmitted_, late_rejected_});
  RecheckVerdict cut;
  cut.cut_now = std::move(flip);
  apply_recheck(cut, in_.measurement_index, rejected_, weights_);
  passes_->restart_budget();
  passes_->forget_solved_start();
  // The iterate was bent around what the probe cut, and a local solve keeps such a fold; the
  // kept set's fresh start (voted on its cost, as after GNC) does not have it.
  if (kept_votes_->enabled()) {
    begin_kept_start_vote(out);
    return;
  }
  begin_inlier_pass(out);
}

void GncAgent::restore_before_probe(std::vector<OutgoingMessage>& out, double rise) {
  GncProbeBase base = probes_->refuse(rise);
  rejected_ = std::move(base.rejected);
  weights_ = std::move(base.weights);
  readmitted_ = base.readmitted;
  late_rejected_ = base.late_rejected;
  // The own block has the same shape whatever the kept set: the next pass starts from it.
  stage_->set_iterate(std::move(base.Y));
  neighbours_current_ = false;
  // The next probe starts from the restored set and iterate, which the passes had settled.
  if (std::optional<std::vector<std::uint64_t>> flip = probes_->next_after_refusal(rejected_)) {
    begin_probe(base.tls, std::move(*flip), out);
    return;
  }
  // One last pass on the restored set (from its converged iterate, so it costs few rounds),
  // then the final solve.
  passes_->last_full_pass();
  begin_inlier_pass(out);
}

}  // namespace tessera
