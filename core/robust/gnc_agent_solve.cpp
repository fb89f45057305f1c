// GncAgent's solves: which solve each GNC step opens (GncSolveStage holds the solve, its layout
// and the iterate), how its messages are tagged with the GNC step, and the messages that came
// while this agent was behind. The state machine that decides which solve comes next is
// gnc_agent.cpp.

#include <algorithm>
#include <cmath>
#include <tessera/robust/gnc_agent.hpp>
#include <utility>
#include <vector>

#include "robust/gnc_exchange.hpp"
#include "robust/gnc_inlier_passes.hpp"
#include "robust/gnc_kept_start_votes.hpp"
#include "robust/gnc_mailbox.hpp"
#include "robust/gnc_messages.hpp"
#include "robust/gnc_outer_loop.hpp"
#include "robust/gnc_solve_stage.hpp"

namespace tessera {

void GncAgent::begin_solve(std::vector<OutgoingMessage>& out) {
  step_ = Step::kSolve;
  trial_weights_sent_ = false;
  const bool neighbours_known = neighbours_current_;
  neighbours_current_ = false;
  // GNC's weighted solves (not the first, plain one) by Newton steps where the interface fits.
  const bool weighted = stage_->kind() == GncSolveKind::kGnc && g_ > first_solve_g_;
  // Trial poses beside the sums: a weighted solve's one (the next weight update's), or every
  // trial of an inlier pass (RobustOptions::pass_poses_ride_trial_sums).
  const bool trial_poses = stage_->kind() == GncSolveKind::kInlierPass
                               ? options_.robust.pass_poses_ride_trial_sums
                               : weighted && send_poses_with_trial();
  pass_trials_sent_ = 0;
  stage_->open(weighted, passes_->capped(), trial_poses, weights_, rejected_);
  if (neighbours_known && stage_->kind() == GncSolveKind::kFinal &&
      !std::isnan(final_start_grad_norm_))
    stage_->know_start(final_start_grad_norm_);
  // A weighted solve by Newton steps, or the final solve from the last pass's point, right
  // after a pose exchange of its start (every agent's steps are the same): its rounds would
  // open with that exchange again and stop at their first status, so it starts at the
  // refinement with the exchange's poses (the same bits).
  // The first solve right after the start vote's pose exchange
  // (RobustOptions::first_solve_takes_start_poses): its rounds take those poses instead of an
  // opening exchange of the same.
  const bool first = stage_->kind() == GncSolveKind::kGnc && g_ == first_solve_g_;
  if (neighbours_known && stage_->may_start_at_refinement())
    pass_on(stage_->start_at_refinement(
                exchange_->neighbours_at(stage_->state().problem().neighbors())),
            out);
  else if (neighbours_known && first)
    pass_on(stage_->solve().start_with_neighbours(
                exchange_->neighbours_at(stage_->state().problem().neighbors())),
            out);
  else
    pass_on(stage_->start(), out);
  const std::uint32_t g = g_;
  // Messages of this solve that came while this agent was behind; once the solve has ended,
  // the rest are of no use.
  for (const ProtocolMessage& m : mail_->begin_solve(g)) {
    if (done_ || g_ != g || step_ != Step::kSolve) break;
    to_solve(m, out);
  }
  if (!done_ && g_ == g && step_ == Step::kSolve && stage_->solve().done()) after_solve(out);
}

void GncAgent::to_solve(const ProtocolMessage& message, std::vector<OutgoingMessage>& out) {
  ProtocolMessage m = message;
  std::visit([&](auto& x) { x.phase -= g_ * kGncStepStride; }, m);
  pass_on(stage_->solve().handle(m), out);
  if (stage_->solve().done()) after_solve(out);
}

// The inner solve's messages, tagged with this GNC step.
void GncAgent::pass_on(std::vector<OutgoingMessage> solve_out, std::vector<OutgoingMessage>& out) {
  for (auto& o : solve_out) {
    std::visit([&](auto& x) { x.phase += g_ * kGncStepStride; }, o.message);
    out.push_back(std::move(o));
  }
  // Beside the trial's sums, which every agent waits for anyway: this step's pose exchange, and
  // the weight update at the trial point.
  if (const Eigen::MatrixXd* trial = stage_->take_trial()) {
    if (stage_->kind() == GncSolveKind::kInlierPass) {  // every trial, numbered
      pass_trials_sent_ = stage_->trials_taken();
      exchange_->publish(*trial, BlockKind::kY, gnc_phase(g_, GncExchange::kPassTrialPoses), out,
                         pass_trials_sent_);
      return;
    }
    exchange_->publish(*trial, BlockKind::kY, gnc_phase(g_, GncExchange::kPoses), out);
    if (options_.robust.weights_ride_trial_sums && (!gather_values_early() || values_held_))
      send_trial_weights(*trial, out);
  }
}

bool GncAgent::gather_values_early() const {
  // Not with pcm-gnc (its check gathers at agent 0 already, and consumes them) nor without a
  // fresh start to use them; the same on every agent.
  return options_.robust.exchanges_ride_along && kept_votes_->enabled() && !in_.pcm &&
         in_.num_agents > 1;
}

bool GncAgent::send_poses_with_trial() const {
  // Every agent decides the same: the options, and the outer loop's state (the summed votes).
  return options_.robust.exchanges_ride_along && options_.robust.gnc_refine_steps == 1 &&
         !outer_->over(options_.robust);
}

void GncAgent::begin_inlier_pass(std::vector<OutgoingMessage>& out) {
  require_kept_connected();
  stage_->to_kept_set(rejected_);
  passes_->open(stage_->pass_refines());
  ++g_;
  begin_solve(out);
}

void GncAgent::solve_without(const std::vector<std::uint64_t>& dropped) {
  stage_->drop(dropped);
}

}  // namespace tessera
