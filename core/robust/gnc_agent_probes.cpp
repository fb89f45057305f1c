// GncAgent's probes: which kept measurements a probe cuts, and how a refused probe restores the
// set and iterate from before it (gnc_probes.hpp holds the budget and the verdicts). The state
// machine that decides when to probe is gnc_agent.cpp.

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/stage_tag.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <tessera/util/input_error.hpp>

#include "robust/gnc_cluster_search.hpp"
#include "robust/gnc_exchange.hpp"
#include "robust/gnc_lead_steps.hpp"
#include "robust/gnc_local_terms.hpp"
#include "robust/gnc_mailbox.hpp"
#include "robust/gnc_messages.hpp"
#include "robust/gnc_outer_loop.hpp"
#include "robust/gnc_probes.hpp"
#include "robust/gnc_solve_setup.hpp"
#include "robust/gnc_votes.hpp"

namespace tessera {

int GncAgent::probes() const {
  return probes_->started();
}

int GncAgent::probes_kept() const {
  return probes_->kept();
}

bool GncAgent::may_probe() const {
  return probes_->may_start(terms_->known_connected(), options_.robust.readmission_passes);
}

std::vector<std::uint64_t> GncAgent::probe_flips(std::vector<std::uint64_t> listed) const {
  // RobustOptions::probe_cut: from GNC's own set the tail side is cut always, never, or where
  // GNC's weighted solves were rounds.
  const ProbeCut rule = options_.robust.probe_cut;
  const bool cut_untouched =
      rule == ProbeCut::kAlways || (rule == ProbeCut::kAuto && !gnc_newton_steps_);
  if (cut_untouched || rejected_ != gnc_rejected_) return listed;
  // Every agent holds the same list and set (the verdict exchange): the same flips everywhere.
  listed.erase(std::remove_if(listed.begin(), listed.end(),
                              [&](std::uint64_t id) {
                                return !std::binary_search(rejected_.begin(), rejected_.end(), id);
                              }),
               listed.end());
  return listed;
}

void GncAgent::begin_probe(double tls, std::vector<std::uint64_t> flip,
                           std::vector<OutgoingMessage>& out) {
  // Every agent holds every agent's probe list (the verdict exchange) and runs the same cluster
  // search: the same flips everywhere.
  probes_->start(GncProbeBase{tls, rejected_, weights_, state_->Y, readmitted_, late_rejected_});
  RecheckVerdict cut;
  cut.cut_now = std::move(flip);
  apply_recheck(cut, in_.measurement_index, rejected_, weights_);
  pass_ = 0;
  last_pass_full_ = false;
  // The iterate was bent around what the probe cut, and a local solve keeps such a fold; the
  // kept set's fresh start (voted on its cost, as after GNC) does not have it.
  if (fresh_start_) {
    require_kept_connected();
    begin_exchange(Step::kKeptStart, out);
    return;
  }
  begin_inlier_pass(out);
}

void GncAgent::restore_before_probe(std::vector<OutgoingMessage>& out, double rise) {
  GncProbeBase base = probes_->take_base();
  rejected_ = std::move(base.rejected);
  weights_ = std::move(base.weights);
  readmitted_ = base.readmitted;
  late_rejected_ = base.late_rejected;
  // The own block has the same shape whatever the kept set: the next pass starts from it.
  state_->Y = std::move(base.Y);
  neighbours_current_ = false;
  if (search_) {
    // The next probe starts from the restored set and iterate, which the passes had settled.
    search_->refused(rise, base.tls);
    if (may_probe())
      if (std::optional<std::vector<std::uint64_t>> flip = search_->next(rejected_)) {
        begin_probe(base.tls, std::move(*flip), out);
        return;
      }
  }
  // One last pass on the restored set (from its converged iterate, so it costs few rounds),
  // then the final solve.
  pass_ = options_.robust.readmission_passes;
  full_pass_next_ = true;
  begin_inlier_pass(out);
}

}  // namespace tessera
