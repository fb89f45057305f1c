// GncAgent's solves: the certified solve each GNC step runs (the first plain one, the weighted
// ones, the inlier passes and the final one), its layout without the dropped measurements, and
// how its messages are tagged with the GNC step. The state machine that decides which solve
// comes next is gnc_agent.cpp.

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

void GncAgent::begin_solve(std::vector<OutgoingMessage>& out) {
  step_ = Step::kSolve;
  const bool neighbours_known = neighbours_current_;
  neighbours_current_ = false;
  solve_.reset();
  // GNC's weighted solves (not the first, plain one) by Newton steps where the interface fits.
  const bool weighted = solve_kind_ == GncSolveKind::kGnc && g_ > first_solve_g_;
  const bool newton_steps = weighted && gnc_refines(options_, *layout_, in_.d);
  solve_options_ = gnc_solve_options(options_, solve_kind_, pass_capped_, newton_steps);
  if (weighted) {
    gnc_newton_steps_ = (weighted_solves_ == 0 || gnc_newton_steps_) && newton_steps;
    ++weighted_solves_;
  }
  std::vector<Measurement> measurements;
  if (solve_kind_ == GncSolveKind::kGnc)
    measurements =
        gnc_solve_measurements(in_.measurements, weights_, weighted, terms_->known_connected());
  else
    measurements = kept_;
  const Eigen::MatrixXd Y = state_ ? state_->Y : in_.Y0;
  if (solve_kind_ == GncSolveKind::kInlierPass) last_pass_start_ = Y;
  state_ = std::make_unique<AgentState>(in_.id, in_.d, *layout_, measurements, Y,
                                        solve_options_.block_update);
  if (solve_options_.refine.enabled &&
      solve_options_.refine.coarse == NewtonRefineOptions::Coarse::kSmoothed)
    // The refinement's coarse space over the graph this solve works on, as the in-process
    // solve of the same graph builds it (every agent the same, no message).
    state_->use_refine_space(std::make_shared<const CoarseSpace>(
        make_coarse_space(in_.num_poses, solve_structure(), in_.owner,
                          solve_options_.refine.coarse_space_options())));
  solve_ = std::make_unique<CertifiedAgent>(*state_, *layout_, solve_options_);
  trial_pending_ = poses_sent_early_ = poses_early_stale_ = false;
  if (newton_steps && send_poses_with_trial())
    solve_->set_trial_observer([this](const Eigen::MatrixXd& Y) {
      // One trial per solve (a single Newton step); after rounds the iterate the last pose
      // exchange holds is not the solve's start, so those take the exchange of their own.
      if (poses_sent_early_ || trial_pending_ || solve_->total_rounds() > 0) return;
      trial_Y_ = Y;
      trial_pending_ = true;
    });
  // A weighted solve by Newton steps right after a pose exchange of its start (every agent's
  // steps are the same): its rounds would open with that exchange again and stop at their first
  // status, so it starts at the refinement with the exchange's poses (the same bits).
  if (newton_steps && neighbours_known && options_.robust.exchanges_ride_along &&
      solve_->can_start_at_refinement()) {
    state_->reset_iterate(state_->Y, exchange_->neighbours_at(state_->problem().neighbors()));
    pass_on(solve_->start_at_refinement(), out);
  } else {
    pass_on(solve_->start(), out);
  }
  const std::uint32_t g = g_;
  // Messages of this solve that came while this agent was behind; once the solve has ended,
  // the rest are of no use.
  for (const ProtocolMessage& m : mail_->begin_solve(g)) {
    if (done_ || g_ != g || step_ != Step::kSolve) break;
    to_solve(m, out);
  }
  if (!done_ && g_ == g && step_ == Step::kSolve && solve_->done()) after_solve(out);
}

void GncAgent::to_solve(const ProtocolMessage& message, std::vector<OutgoingMessage>& out) {
  ProtocolMessage m = message;
  std::visit([&](auto& x) { x.phase -= g_ * kGncStepStride; }, m);
  pass_on(solve_->handle(m), out);
  if (solve_->done()) after_solve(out);
}

// Endpoints of the measurements the current solve works on, file order: the kept set for the
// passes and the final solve, the whole graph for GNC's weighted solves.
std::vector<std::pair<std::uint32_t, std::uint32_t>> GncAgent::solve_structure() const {
  return solve_kind_ == GncSolveKind::kGnc ? in_.structure
                                           : inlier_structure(in_.structure, rejected_);
}

// The inner solve's messages, tagged with this GNC step.
void GncAgent::pass_on(std::vector<OutgoingMessage> solve_out, std::vector<OutgoingMessage>& out) {
  for (auto& o : solve_out) {
    std::visit([&](auto& x) { x.phase += g_ * kGncStepStride; }, o.message);
    out.push_back(std::move(o));
  }
  if (trial_pending_) {
    // Beside the trial's sums, which every agent waits for anyway: this step's pose exchange.
    exchange_->publish(trial_Y_, BlockKind::kY, gnc_phase(g_, GncExchange::kPoses), out);
    trial_pending_ = false;
    poses_sent_early_ = true;
  }
}

bool GncAgent::gather_values_early() const {
  // Not with pcm-gnc (its check gathers at agent 0 already, and consumes them) nor without a
  // fresh start to use them; the same on every agent.
  return options_.robust.exchanges_ride_along && fresh_start_ && !in_.pcm && in_.num_agents > 1;
}

bool GncAgent::send_poses_with_trial() const {
  // Every agent decides the same: the options, and the outer loop's state (the summed votes).
  return options_.robust.exchanges_ride_along && options_.robust.gnc_refine_steps == 1 &&
         !outer_->over(options_.robust);
}

void GncAgent::begin_inlier_pass(std::vector<OutgoingMessage>& out) {
  require_kept_connected();
  gnc_kept_measurements(in_.measurements, in_.measurement_index, rejected_, kept_, kept_index_);
  solve_without(rejected_);
  solve_kind_ = GncSolveKind::kInlierPass;
  // A pass that hands over to the refinement is solved to the tolerance even while its set may
  // still change: from the last iterate that costs fewer message steps than the capped rounds.
  pass_capped_ = options_.robust.recheck_max_rounds > 0 && !full_pass_next_ &&
                 !pass_refines(options_, *layout_, in_.d);
  full_pass_next_ = false;
  pass_from_solved_ = last_pass_full_;
  last_pass_full_ = false;
  ++g_;
  begin_solve(out);
}

void GncAgent::solve_without(const std::vector<std::uint64_t>& dropped) {
  auto layout = std::make_unique<BlockLayout>(
      make_block_layout(in_.num_poses, structure_without(in_.structure, dropped), in_.owner));
  // The state refers to the layout: keep the iterate as the next start, then replace both.
  if (state_) in_.Y0 = state_->Y;
  solve_.reset();
  state_.reset();
  layout_ = std::move(layout);
}

}  // namespace tessera
