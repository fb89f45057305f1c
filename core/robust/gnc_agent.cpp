// GncAgent's state machine: its construction, the outer loop's transitions after each solve and
// each exchange (after_solve, after_exchange) and the end of the run. The opening steps (pcm-gnc's
// check, the start vote) are gnc_agent_opening.cpp, the solves gnc_agent_solve.cpp, the exchanges
// gnc_agent_exchanges.cpp, the probes gnc_agent_probes.cpp, the results gnc_agent_results.cpp.

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <tessera/problem/lifting.hpp>
#include <tessera/robust/gnc_agent.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <tessera/robust/weighted_graph.hpp>
#include <tessera/util/input_error.hpp>

#include "robust/gnc_exchange.hpp"
#include "robust/gnc_inlier_passes.hpp"
#include "robust/gnc_kept_start_votes.hpp"
#include "robust/gnc_lead_steps.hpp"
#include "robust/gnc_local_terms.hpp"
#include "robust/gnc_mailbox.hpp"
#include "robust/gnc_messages.hpp"
#include "robust/gnc_outer_loop.hpp"
#include "robust/gnc_probe_stage.hpp"
#include "robust/gnc_solve_stage.hpp"
#include "robust/gnc_votes.hpp"

namespace tessera {

GncAgent::GncAgent(GncAgentInput input, const GncDistributedOptions& options, bool final_solve)
    : in_(std::move(input)), options_(options), final_solve_wanted_(final_solve) {
  options_.validate();
  const std::size_t m = in_.measurements.size();
  if (in_.measurement_index.size() != m)
    throw std::invalid_argument("GncAgent: one file position per measurement expected");
  if (!in_.known_inlier.empty() && in_.known_inlier.size() != in_.structure.size())
    throw std::invalid_argument("GncAgent: one known-inlier flag per measurement expected");
  if (!std::is_sorted(in_.measurement_index.begin(), in_.measurement_index.end()))
    throw std::invalid_argument("GncAgent: measurements must be in file order");
  if (in_.Y0_known.size() > 0 &&
      (in_.Y0_known.rows() != in_.Y0.rows() || in_.Y0_known.cols() != in_.Y0.cols()))
    throw std::invalid_argument("GncAgent: the known inliers' start must have Y0's shape");
  // Every solve is a GNC step of the phase field: the start vote, the first, the weighted
  // ones, the passes and the final one.
  if (static_cast<long long>(options_.robust.max_outer_iterations) +
          options_.robust.readmission_passes + 4 >
      static_cast<long long>(kMaxGncSteps))
    throw InputError("RobustOptions.max_outer_iterations + readmission_passes must be <= " +
                     std::to_string(kMaxGncSteps - 4) + " for the distributed solve");
  kept_votes_ = std::make_unique<GncKeptStartVotes>(
      in_.kept_set_start && in_.initialization == DistributedInit::kChordal);
  passes_ = std::make_unique<GncInlierPasses>(options_.robust);
  dropped_.assign(in_.measurements.size(), false);
  base_ = std::make_unique<BlockLayout>(make_block_layout(in_.num_poses, in_.structure, in_.owner));
  terms_ = std::make_unique<GncLocalTerms>(in_, options_.robust, *base_);
  stage_ =
      std::make_unique<GncSolveStage>(in_, options_, terms_->known_connected(), std::move(in_.Y0));
  exchange_ = std::make_unique<GncExchangeBook>(in_, *terms_, *base_);
  mail_ = std::make_unique<GncMailbox>(in_.id);
  outer_ = std::make_unique<GncOuterLoop>();
  recheck_ = std::make_unique<RecheckVerdict>();
  probes_ =
      std::make_unique<GncProbeStage>(in_, options_, terms_->known(), terms_->known_connected());
  weights_.assign(m, 1.0);
}

GncAgent::~GncAgent() = default;

int GncAgent::weights_at(double mu, const Eigen::MatrixXd& Y, const Eigen::MatrixXd& neighbours,
                         const std::vector<bool>& skip, std::vector<double>& w) const {
  int crossed = 0;
  const bool falls_only = options_.robust.mu_step_hold == MuStepHold::kFalls;
  for (std::size_t k : terms_->owned())
    if (terms_->may_reject(k) && !skip[k]) {
      const double wk = tls_weight(terms_->residual_squared(k, Y, neighbours), terms_->c2(), mu);
      // RobustOptions::mu_step_hold: what holds the adaptive step of mu back.
      if (falls_only ? wk < 0.5 && w[k] >= 0.5 : (wk >= 0.5) != (w[k] >= 0.5)) ++crossed;
      w[k] = wk;
    }
  return crossed;
}

void GncAgent::begin_kept_start_vote(std::vector<OutgoingMessage>& out) {
  require_kept_connected();  // before initializing the kept set
  begin_exchange(Step::kKeptStart, out);
}

void GncAgent::require_kept_connected() const {
  // The kept set must connect every pose (every agent checks the same set).
  const std::size_t parts =
      components_without(in_.num_poses, in_.d, in_.structure, rejected_, false, terms_->known());
  if (parts > 1)
    throw InputError("robust solve: " + std::to_string(rejected_.size()) + " of " +
                     std::to_string(in_.structure.size()) +
                     " measurements look like outliers, and the kept ones split the poses into " +
                     std::to_string(parts) +
                     " unconnected parts, so no estimate is defined (too few consistent "
                     "measurements; try --known-inliers odometry or a larger --inlier-threshold)");
}

void GncAgent::begin_rejected(std::vector<OutgoingMessage>& out) {
  // No weight exchange yet (nothing could be an outlier), or the rejected set's own exchange.
  if (outer_->outer() == 0 || !options_.robust.exchanges_ride_along) {
    begin_exchange(Step::kRejected, out);
    return;
  }
  // The weights have not changed since the last weight exchange (a last weighted solve moves
  // only the iterate), which brought every other agent's weights below 1/2: the rejected set is
  // known here as the exchange would have brought it, with TLS's verdict after an early end.
  rejected_ = rejected_by_weight(*terms_, in_.measurement_index, weights_);
  for (const auto& [id, w] : low_weights_)
    if ((jumped_ ? tls_verdict_weight(w, outer_->mu()) : w) < 0.5) rejected_.push_back(id);
  step_ = Step::kRejected;
  after_exchange(out);
}

bool GncAgent::final_solve_runs() const {
  return options_.solver.certify || options_.robust.final_refine;
}

void GncAgent::finish(std::vector<OutgoingMessage>& out) {
  // Before the final solve (here or the caller's): is the passes' iterate worse over the kept
  // set than the kept set's own fresh start (GncDistributedOptions::final_kept_set_start)? Then
  // it is a fold, and the passes judged their set on it: they run again from the fresh start.
  // Not when the outcome is already known (GncKeptStartVotes): the iterate stays.
  if (kept_votes_->final_vote_due(final_solve_runs() && options_.final_kept_set_start, rejected_)) {
    kept_votes_->begin(GncKeptStartVotes::Kind::kFinal);
    begin_kept_start_vote(out);
    return;
  }
  // The final solve starts where the last pass ended, whose pose exchange every agent holds
  // (RobustOptions::kept_solves_start_at_refinement).
  final_start_grad_norm_ = options_.robust.kept_solves_start_at_refinement && neighbours_current_
                               ? stage_->pass_grad_norm()
                               : std::numeric_limits<double>::quiet_NaN();
  if (!final_solve_runs() || !final_solve_wanted_) {
    done_ = true;
    step_ = Step::kDone;
    return;
  }
  // The certificate once, on the set that stays (re-admission ran on uncertified solves: the
  // staircase may raise the rank, which a further pass could not start from).
  stage_->to_final();
  ++g_;
  begin_solve(out);
}

void GncAgent::start_kept_set(std::vector<OutgoingMessage>& out) {
  // Agent 0: the kept set's initialization, each agent's block sent, its own kept.
  // With the iterate's cost known from the weights, the start's own cost goes with it: the vote
  // needs no exchange (RobustOptions::kept_vote_rides_weights).
  double cost = 0;
  const Eigen::MatrixXd X = kept_set_start(exchange_->kept_values(), in_, rejected_.size(),
                                           static_cast<int>(stage_->iterate().rows()),
                                           iterate_kept_cost_ ? &cost : nullptr);
  exchange_->candidate_cost().reset();
  if (iterate_kept_cost_) exchange_->candidate_cost() = cost;
  // With values_held_, each agent's neighbours' poses of the start too: no pose exchange of the
  // start follows.
  std::vector<std::vector<std::size_t>> nb(static_cast<std::size_t>(in_.num_agents));
  if (values_held_) {
    nb = cut_neighbours(in_);
    exchange_->candidate_neighbours() = gather_pose_columns(X, terms_->neighbours(), in_.d);
  }
  for (std::uint32_t a = 1; a < static_cast<std::uint32_t>(in_.num_agents); ++a)
    out.push_back(OutgoingMessage{
        kept_start_block(gather_pose_columns(X, base_->poses[a], in_.d), base_->poses[a], in_.d,
                         gnc_phase(g_, GncExchange::kKeptStart),
                         gather_pose_columns(X, nb[a], in_.d), nb[a]),
        false,
        {a}});
  exchange_->candidate() = gather_pose_columns(X, base_->poses[0], in_.d);
  if (exchange_->candidate_cost()) {
    RoundStatusMessage st;
    st.cost = *exchange_->candidate_cost();
    broadcast_status(std::move(st), 0, gnc_phase(g_, GncExchange::kKeptStart), in_.num_agents, out);
  }
}

void GncAgent::after_solve(std::vector<OutgoingMessage>& out) {
  stage_->tally();
  if (stage_->kind() == GncSolveKind::kFinal) {
    done_ = true;
    step_ = Step::kDone;
    return;
  }
  if (stage_->kind() == GncSolveKind::kInlierPass) {
    passes_->solved();
    kept_votes_->set_last_pass_cost(passes_->capped() ? std::numeric_limits<double>::quiet_NaN()
                                                      : stage_->last_cost());
    if (probes_->running() && passes_->budget_spent()) {
      // The probe's passes ran out before a verdict could judge it: it does not stay.
      restore_before_probe(out);
      return;
    }
    if (passes_->budget_spent() || rejected_.empty()) {
      // Without a final solve to follow, the last pass must reach the tolerance itself.
      if (passes_->capped() && !final_solve_runs()) {
        passes_->solve_next_fully();
        begin_inlier_pass(out);
        return;
      }
      finish(out);
      return;
    }
    begin_exchange(Step::kPoses, out);
    return;
  }
  if (g_ > first_solve_g_ && outer_->over(options_.robust)) {
    begin_rejected(out);
    return;
  }
  if (g_ > first_solve_g_ && stage_->newton_step_untrusted(options_.robust.newton_step_trust)) {
    // RobustOptions::newton_step_trust: the Newton model did not hold, so its end is no
    // minimiser to weigh at; the same weights are solved by rounds from the step's start. The
    // trial's poses and weights that went out beside its sums are of no use (later copies are
    // dropped on arrival: their step is left).
    mail_->discard(gnc_phase(g_, GncExchange::kPoses));
    mail_->discard(gnc_phase(g_, GncExchange::kTrialWeights));
    trial_weights_sent_ = false;
    stage_->solve_again_by_rounds();
    ++g_;
    begin_solve(out);
    return;
  }
  if (stage_->poses_sent_early()) stage_->judge_early_poses();
  begin_exchange(Step::kPoses, out);
}

void GncAgent::after_exchange(std::vector<OutgoingMessage>& out) {
  switch (step_) {
    case Step::kPoses:
      neighbours_current_ = true;
      if (stage_->kind() == GncSolveKind::kInlierPass)
        begin_exchange(Step::kReadmitted, out);
      else
        begin_exchange(outer_->started() ? Step::kWeights : Step::kVotes, out);
      return;
    case Step::kVotes:
      outer_->start(exchange_->largest_vote(), terms_->c2(), options_.robust);
      if (outer_->converged())
        begin_rejected(out);
      else
        begin_exchange(Step::kWeights, out);
      return;
    case Step::kWeights:
      after_weights(out);
      return;
    case Step::kRejected:
      after_rejected(out);
      return;
    case Step::kKeptStart:
      if (in_.id == 0) start_kept_set(out);
      // Both starts' neighbour poses are here already: the iterate's from the last pose
      // exchange, the fresh start's from agent 0.
      if (values_held_ && neighbours_current_) {
        // Both costs are here too: the iterate's from the last weights, the start's from agent 0.
        if (iterate_kept_cost_ && exchange_->candidate_cost()) {
          const std::pair<double, double> sums{*iterate_kept_cost_, *exchange_->candidate_cost()};
          iterate_kept_cost_.reset();
          after_candidate_votes(sums, out);
          return;
        }
        begin_exchange(Step::kCandidateVotes, out);
        return;
      }
      begin_exchange(Step::kCandidatePoses, out);
      return;
    case Step::kPcm:
      after_pcm(out);
      return;
    case Step::kStartPoses:
      begin_exchange(Step::kStartVotes, out);
      return;
    case Step::kStartVotes:
      after_start_votes(out);
      return;
    case Step::kCandidatePoses:
      neighbours_current_ = true;
      begin_exchange(Step::kCandidateVotes, out);
      return;
    case Step::kCandidateVotes:
      after_candidate_votes(exchange_->summed_votes(), out);
      return;
    case Step::kReadmitted:
      after_verdict(out);
      return;
    default:
      return;
  }
}

void GncAgent::after_rejected(std::vector<OutgoingMessage>& out) {
  std::sort(rejected_.begin(), rejected_.end());
  gnc_rejected_ = rejected_;
  // Nothing rejected: the GNC iterate is already the plain solve's.
  if (rejected_.empty()) iterate_kept_cost_.reset();
  if (kept_votes_->enabled() && !rejected_.empty()) {
    begin_kept_start_vote(out);
    return;
  }
  begin_inlier_pass(out);
}

void GncAgent::after_weights(std::vector<OutgoingMessage>& out) {
  const auto [spread, crossed] = exchange_->summed_votes();
  const bool jump =
      outer_->after_update(spread, static_cast<int>(crossed), exchange_->summed_near_bound(),
                           options_.robust, stage_->newton_steps_only());
  jumped_ = jump;
  // The early end's rejected set follows from these weights with no exchange: its cost at the
  // iterate is the one the weights messages carried.
  iterate_kept_cost_.reset();
  if (jump && kept_vote_rides_weights()) iterate_kept_cost_ = exchange_->summed_kept_cost();
  if (jump)
    for (std::size_t k = 0; k < weights_.size(); ++k)
      if (terms_->may_reject(k) && !dropped_[k])
        weights_[k] = tls_verdict_weight(weights_[k], outer_->mu());
  if (weight_observer_) weight_observer_(outer_->outer(), in_.measurement_index, weights_);
  if (jump) {
    begin_rejected(out);
    return;
  }
  if (terms_->known_connected()) {
    // This step's block layout: without the cut measurements of weight 0 (every agent's).
    std::sort(zero_cut_.begin(), zero_cut_.end());
    solve_without(zero_cut_);
  }
  ++g_;
  begin_solve(out);
}

void GncAgent::after_candidate_votes(std::pair<double, double> sums,
                                     std::vector<OutgoingMessage>& out) {
  iterate_kept_cost_.reset();
  const auto [at_iterate, at_candidate] = sums;
  const GncKeptStartVotes::Kind vote = kept_votes_->ended(rejected_, at_candidate);
  const bool fresh = at_candidate < at_iterate;
  if (fresh) {
    stage_->set_iterate(exchange_->candidate());
    // The fresh start's neighbour poses came with it (agent 0's answer, or the two starts' pose
    // exchange): a pass may start at its refinement from there.
    // (Every agent decides the same: the option alone.)
    neighbours_current_ = options_.robust.kept_solves_start_at_refinement;
    if (neighbours_current_) exchange_->adopt_candidate_neighbours();
  }
  exchange_->candidate().resize(0, 0);
  exchange_->forget_candidate_neighbours();
  passes_->forget_solved_start();
  if (vote == GncKeptStartVotes::Kind::kFinal) {
    if (!fresh) {
      finish(out);  // the iterate stays: on to the final solve
      return;
    }
    passes_->restart_budget();  // the passes again, with their own budget
  }
  // A stall vote the iterate won: its set solved to the tolerance, as without the vote.
  if (vote == GncKeptStartVotes::Kind::kStall && !fresh) passes_->solve_next_fully();
  begin_inlier_pass(out);
}

void GncAgent::after_verdict(std::vector<OutgoingMessage>& out) {
  passes_->judged();
  if (recheck_->empty()) {
    after_unchanged_verdict(out);
    return;
  }
  const RecheckCounts counts = apply_recheck(*recheck_, in_.measurement_index, rejected_, weights_);
  readmitted_ += counts.readmitted;
  late_rejected_ += counts.late_rejected;
  if (probes_->back_at_base(rejected_)) {
    // The passes took back exactly what the probe changed: it ends here, not kept (its
    // TLS cost could differ from the base's only by the solves' accuracy).
    restore_before_probe(out);
    return;
  }
  begin_inlier_pass(out);
}

void GncAgent::after_unchanged_verdict(std::vector<OutgoingMessage>& out) {
  // No change at a rough solution: the same set once more, solved to the tolerance; but a pass
  // that started from a solved pass only settled that pass's flips, and its verdict stands
  // (RobustOptions::recheck_confirm_solved) when a solve to the tolerance follows.
  if (passes_->unchanged_needs_full_pass(final_solve_runs())) {
    if (options_.stall_kept_set_start && kept_votes_->stall_vote_due(rejected_)) {
      kept_votes_->begin(GncKeptStartVotes::Kind::kStall);
      begin_kept_start_vote(out);
      return;
    }
    passes_->solve_next_fully();
    begin_inlier_pass(out);
    return;
  }
  const double tls = exchange_->summed_votes().first;
  if (probes_->running()) {
    const double before = probes_->base_tls();
    if (!probes_->keeps(rejected_, tls)) {
      restore_before_probe(out, tls - before);
      return;
    }
  }
  if (std::optional<std::vector<std::uint64_t>> flip = probes_->next(
          std::move(recheck_->probe), rejected_, gnc_rejected_, stage_->newton_steps_only())) {
    begin_probe(tls, std::move(*flip), out);
    return;
  }
  finish(out);
}

std::vector<OutgoingMessage> GncAgent::handle(const ProtocolMessage& message) {
  std::vector<OutgoingMessage> out;
  if (done_) return out;
  if (mail_->add(message))
    to_solve(message, out);
  else if (step_ != Step::kSolve)
    take_exchange(out);
  return out;
}

std::size_t GncAgent::messages_needed() const {
  if (done_) return 0;
  if (step_ == Step::kSolve) return std::max<std::size_t>(stage_->solve().messages_needed(), 1);
  return mail_->messages_needed();
}

std::optional<AwaitedMessages> GncAgent::awaited() const {
  if (done_) return std::nullopt;
  if (step_ == Step::kSolve) {
    std::optional<AwaitedMessages> a = stage_->solve().awaited();
    if (a) a->phase += g_ * kGncStepStride;
    return a;
  }
  return mail_->awaited();
}

}  // namespace tessera
