// GncAgent's exchange steps: what each step of GNC's own exchanges computes from this agent's view
// and sends to whom (GncAgent::Step), which exchange a step is, and reading a completed exchange
// into the book. The state machine that decides which step comes next is gnc_agent.cpp; the
// messages' layout is gnc_messages.hpp.

#include <algorithm>
#include <stdexcept>
#include <tessera/robust/gnc_agent.hpp>
#include <tessera/robust/tls_weights.hpp>
#include <utility>
#include <vector>

#include "robust/gnc_exchange.hpp"
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

namespace {

std::vector<int> as_ints(const std::vector<std::uint32_t>& ids) {
  return {ids.begin(), ids.end()};
}

}  // namespace

void GncAgent::begin_exchange(Step step, std::vector<OutgoingMessage>& out) {
  // Exchanges whose messages went out beside a solve's trial sums, where that trial stands.
  if (step == Step::kPoses && pass_trials_sent_ > 0 && begin_pass_trial_poses(out)) return;
  if (step == Step::kWeights && trial_weights_sent_ && begin_trial_weights(out)) return;
  step_ = step;
  const std::uint32_t phase = gnc_phase(g_, exchange());
  const auto me = static_cast<std::uint32_t>(in_.id);
  exchange_->begin();
  // A gather at agent 0 (the consistency check's values, the kept set's start) waits twice: for
  // the values, then for agent 0's answer.
  // The poses sent beside a weighted solve's trial sums are no step of their own; the start
  // vote's is the first solve's opening exchange, counted with its solve stage
  // (RobustOptions::first_solve_takes_start_poses), where that solve runs
  // (RobustOptions::weigh_at_start: none).
  const bool early = (step == Step::kPoses && stage_->poses_sent_early()) ||
                     (step == Step::kStartPoses && options_.robust.first_solve_takes_start_poses &&
                      !weighs_at_start());
  exchange_steps_ += step == Step::kPcm || (step == Step::kKeptStart && !values_held_) ? 2
                     : early                                                           ? 0
                                                                                       : 1;
  if (step == Step::kKeptStart && values_held_ && in_.id == 0) {
    // The kept ones of the values held since mu's start: nothing to wait for.
    GatheredValues& kept = exchange_->kept_values();
    kept.clear();
    for (const auto& v : exchange_->held_values())
      if (!std::binary_search(rejected_.begin(), rejected_.end(), v.first)) kept.push_back(v);
    after_exchange(out);
    return;
  }
  bool values_too = false;  // agent 0's exchange takes the others' values beside their status
  // Whom this agent hears from: a pose exchange from its block neighbours (each sends what it
  // was sent), a status exchange from every other agent, each of which answers with its own.
  std::vector<int> from = as_ints(other_agents(me, in_.num_agents));
  switch (step) {
    case Step::kPoses:
    case Step::kStartPoses:
    case Step::kCandidatePoses:
      send_poses(phase, out);
      from = base_->adjacent[static_cast<std::size_t>(in_.id)];
      break;
    case Step::kPcm:
      from = exchange_->gather_values_at_lead(gnc_phase(g_, GncExchange::kPcmValues), nullptr, out);
      break;
    case Step::kKeptStart:
      from = values_held_ ? std::vector<int>{0}  // agent 0's answer
                          : exchange_->gather_values_at_lead(
                                gnc_phase(g_, GncExchange::kKeptValues), &rejected_, out);
      // Beside agent 0's start, its cost over the kept set (the vote's second sum).
      values_too = in_.id != 0 && iterate_kept_cost_.has_value();
      break;
    case Step::kWeights:
      values_too = send_weights(phase, out);
      break;
    default:
      send_status(phase, out);
      break;
  }
  mail_->begin_exchange(phase, std::move(from), values_too);
  take_exchange(out);
}

void GncAgent::send_poses(std::uint32_t phase, std::vector<OutgoingMessage>& out) {
  const Eigen::MatrixXd& Y = stage_->iterate();  // the iterate, or the start before a solve
  switch (step_) {
    case Step::kPoses:
      // Weights are computed at the iterate itself: the owners' public poses of every
      // measurement (the base layout: a measurement out of the current solve still needs
      // its residual).
      if (stage_->poses_sent_early()) {
        if (!stage_->poses_early_stale()) exchange_->expect_poses(Y.rows(), false);
        return;
      }
      exchange_->expect_poses(Y.rows(), false);
      exchange_->publish(Y, BlockKind::kY, phase, out);
      return;
    case Step::kStartPoses:
      // Both starts' public poses: the solver's initialization (kind Y) and the known
      // inliers' (kind P).
      exchange_->expect_poses(Y.rows(), true);
      exchange_->publish(Y, BlockKind::kY, phase, out);
      exchange_->publish(in_.Y0_known, BlockKind::kP, phase, out);
      return;
    default:  // Step::kCandidatePoses
      // Both starts' public poses: the iterate's (kind Y) and the other one's (kind P).
      exchange_->expect_poses(Y.rows(), true);
      exchange_->publish(Y, BlockKind::kY, phase, out);
      exchange_->publish(exchange_->candidate(), BlockKind::kP, phase, out);
      return;
  }
}

void GncAgent::send_status(std::uint32_t phase, std::vector<OutgoingMessage>& out) {
  const Eigen::MatrixXd& Y = stage_->iterate();  // the iterate, or the start before a solve
  RoundStatusMessage st;
  switch (step_) {
    case Step::kStartVotes:
      // The TLS cost of each measurement at both starts, summed by its weight owner.
      exchange_->own_vote() = start_vote_costs(*terms_, Y, exchange_->neighbours(), in_.Y0_known,
                                               exchange_->candidate_neighbours());
      st = vote_message(exchange_->own_vote());
      break;
    case Step::kCandidateVotes:
      // Each kept measurement's cost at both starts, summed by its weight owner.
      exchange_->own_vote() =
          kept_set_costs(*terms_, in_.measurement_index, rejected_, Y, exchange_->neighbours(),
                         exchange_->candidate(), exchange_->candidate_neighbours());
      st = vote_message(exchange_->own_vote());
      break;
    case Step::kVotes:
      // mu's start needs the largest residual over every measurement that may be rejected.
      exchange_->own_vote() = {
          largest_rejectable_residual(*terms_, dropped_, Y, exchange_->neighbours()), 0};
      st = vote_message(exchange_->own_vote());
      break;
    case Step::kRejected:
      rejected_ = rejected_by_weight(*terms_, in_.measurement_index, weights_);
      st.measurement_ids = rejected_;
      break;
    case Step::kReadmitted:
      // TLS's own verdict at the kept set's solution (gnc_votes.hpp); every agent gathers all.
      // With it the probe's list (only used when nothing else changes) and the TLS cost a probe
      // is judged by.
      *recheck_ =
          recheck_verdict(*terms_, in_.measurement_index, rejected_, Y, exchange_->neighbours(),
                          probes_->may_follow() ? options_.robust.probe_ratio : 0.0,
                          options_.robust.probe_tail_ratio);
      exchange_->own_vote() = {tls_cost(*terms_, Y, exchange_->neighbours()), 0};
      st = readmitted_message(*recheck_, exchange_->own_vote().first);
      break;
    default:  // not a status exchange: begin_exchange() sends it otherwise
      throw std::logic_error("GncAgent: no status exchange at this step");
  }
  broadcast_status(std::move(st), static_cast<std::uint32_t>(in_.id), phase, in_.num_agents, out);
}

int GncAgent::near_bound_at(const std::vector<bool>& skip, const Eigen::MatrixXd& Y,
                            const Eigen::MatrixXd& neighbours) const {
  // Without the early end every update counts as "near", so GNC never ends early.
  if (options_.robust.jump_band <= 0) return 1;
  // RobustOptions::jump_band_max: residuals beyond the bound whose weight at mu is not yet 0
  // (r^2 < (mu + 1) / mu c^2) hold the end back too, up to the cap.
  const double mu = outer_->mu();
  const double band = mu > 0 ? std::max(options_.robust.jump_band,
                                        std::min((mu + 1) / mu, options_.robust.jump_band_max))
                             : options_.robust.jump_band;
  return near_bound_count(*terms_, skip, Y, neighbours, band, options_.robust.jump_band_inside);
}

bool GncAgent::kept_vote_rides_weights() const {
  return options_.robust.kept_vote_rides_weights && options_.robust.exchanges_ride_along &&
         kept_votes_->enabled();
}

double GncAgent::kept_cost_at(const std::vector<double>& w, const Eigen::MatrixXd& Y,
                              const Eigen::MatrixXd& neighbours) const {
  if (!kept_vote_rides_weights()) return 0;
  // As the vote sums it (kept_set_costs): the kept measurements this agent weighs, in order;
  // kept is what the rejected set after an early end keeps (GncAgent::after_weights).
  double cost = 0;
  for (std::size_t k : terms_->owned()) {
    const double verdict =
        terms_->may_reject(k) && !dropped_[k] ? tls_verdict_weight(w[k], outer_->mu()) : w[k];
    if (verdict >= 0.5) cost += terms_->residual_squared(k, Y, neighbours);
  }
  return cost;
}

GncAgent::WeightUpdate GncAgent::weight_update(std::vector<double> w, const Eigen::MatrixXd& Y,
                                               const Eigen::MatrixXd& neighbours,
                                               const std::vector<bool>& skip) const {
  WeightUpdate u;
  const int crossed = weights_at(outer_->mu(), Y, neighbours, skip, w);
  u.vote = {weight_spread(*terms_, w), crossed};
  u.near = near_bound_at(skip, Y, neighbours);
  u.zero_cut = zero_weight_cut(*terms_, in_.measurements, in_.owner, in_.measurement_index, w);
  u.kept_cost = kept_cost_at(w, Y, neighbours);
  u.weights = std::move(w);
  return u;
}

void GncAgent::adopt_weights(WeightUpdate u) {
  weights_ = std::move(u.weights);
  zero_cut_ = std::move(u.zero_cut);
  exchange_->own_vote() = u.vote;
  exchange_->own_near_bound() = u.near;
  exchange_->own_kept_cost() = u.kept_cost;
}

void GncAgent::broadcast_weights(std::uint32_t phase, const WeightUpdate& u,
                                 std::vector<OutgoingMessage>& out) const {
  const auto me = static_cast<std::uint32_t>(in_.id);
  for (std::uint32_t a : other_agents(me, in_.num_agents)) {
    RoundStatusMessage st =
        weights_message(a, u.vote.first, static_cast<int>(u.vote.second), static_cast<int>(u.near),
                        in_, *terms_, u.weights, options_.robust.exchanges_ride_along, u.kept_cost);
    st.phase = phase;
    st.sender = me;
    out.push_back(OutgoingMessage{std::move(st), false, {a}});
  }
}

void GncAgent::send_trial_weights(const Eigen::MatrixXd& Y, std::vector<OutgoingMessage>& out) {
  // The neighbours' poses at the trial point, in the exchange book's columns (the base layout's):
  // the solve's neighbours are known there (their translations solved as this agent's). The
  // other end of a cut measurement of weight 0 may be no neighbour of the solve's layout: its
  // weight stays 0 and it is not near the bound (RobustOptions::weights_ride_trial_sums).
  const std::vector<std::size_t>& nb = terms_->neighbours();
  const std::vector<std::size_t>& solve_nb = stage_->state().problem().neighbors();
  const Eigen::MatrixXd& Yn = stage_->trial_neighbours();
  const Eigen::Index w = in_.d + 1;
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(Y.rows(), w * static_cast<Eigen::Index>(nb.size()));
  std::vector<bool> held(in_.num_poses, false);
  for (std::size_t j = 0; j < solve_nb.size(); ++j) {
    const auto c = std::lower_bound(nb.begin(), nb.end(), solve_nb[j]) - nb.begin();
    if (c == static_cast<std::ptrdiff_t>(nb.size()) ||
        nb[static_cast<std::size_t>(c)] != solve_nb[j])
      continue;
    N.middleCols(w * c, w) = Yn.middleCols(w * static_cast<Eigen::Index>(j), w);
    held[solve_nb[j]] = true;
  }
  std::vector<bool> out_of_reach = dropped_;
  for (std::size_t k : terms_->owned()) {
    const Measurement& m = in_.measurements[k];
    const std::size_t other = in_.owner[m.i] == in_.id ? m.j : m.i;
    if (in_.owner[other] == in_.id || held[other]) continue;
    if (terms_->may_reject(k) && weights_[k] != 0)
      throw std::logic_error("GncAgent: a weighted measurement's other end is off the solve");
    out_of_reach[k] = true;
  }
  trial_update_ = weight_update(weights_, Y, N, out_of_reach);
  broadcast_weights(gnc_phase(g_, GncExchange::kTrialWeights), trial_update_, out);
  trial_weights_sent_ = true;
}

bool GncAgent::begin_pass_trial_poses(std::vector<OutgoingMessage>& out) {
  // An inlier pass's trial poses came beside their sums: the last accepted one's are the
  // pass's point (RobustOptions::pass_poses_ride_trial_sums); the others are of no use.
  const std::uint32_t phase = gnc_phase(g_, GncExchange::kPassTrialPoses);
  const std::uint32_t take = stage_->last_accepted_trial();
  for (std::uint32_t t = 1; t <= pass_trials_sent_; ++t)
    if (t != take) mail_->discard(phase, t);
  pass_trials_sent_ = 0;
  if (take == 0) return false;
  step_ = Step::kPoses;
  exchange_->begin();
  exchange_->expect_poses(stage_->iterate().rows(), false);
  mail_->begin_trial_exchange(phase, take, base_->adjacent[static_cast<std::size_t>(in_.id)]);
  take_exchange(out);
  return true;
}

bool GncAgent::begin_trial_weights(std::vector<OutgoingMessage>& out) {
  trial_weights_sent_ = false;
  if (!stage_->poses_sent_early() || stage_->poses_early_stale()) {
    // The trial was not accepted: the weights go out at the iterate as ever.
    mail_->discard(gnc_phase(g_, GncExchange::kTrialWeights));
    return false;
  }
  // The accepted trial point is the iterate, to the bit: its weight update is this step's, sent
  // already; the others' came beside the trial's sums (no step of its own).
  step_ = Step::kWeights;
  exchange_->begin();
  low_weights_.clear();
  adopt_weights(std::move(trial_update_));
  mail_->begin_exchange(gnc_phase(g_, GncExchange::kTrialWeights),
                        as_ints(other_agents(static_cast<std::uint32_t>(in_.id), in_.num_agents)));
  take_exchange(out);
  return true;
}

bool GncAgent::send_weights(std::uint32_t phase, std::vector<OutgoingMessage>& out) {
  low_weights_.clear();
  WeightUpdate u = weight_update(weights_, stage_->iterate(), exchange_->neighbours(), dropped_);
  broadcast_weights(phase, u, out);
  adopt_weights(std::move(u));
  if (!gather_values_early() || values_held_) return false;
  // Beside the first weights (clean data has none), once: the values of the measurements this
  // agent weighs, to agent 0.
  values_held_ = true;
  if (in_.id != 0) {
    out.push_back(OutgoingMessage{owned_values_block(in_, *terms_, nullptr, phase), false, {0}});
    return false;
  }
  exchange_->held_values().clear();
  append_owned_values(in_, *terms_, nullptr, exchange_->held_values());
  return true;  // agent 0 takes the others' values beside their weights
}

GncExchange GncAgent::exchange() const {
  switch (step_) {
    case Step::kPoses:
      return GncExchange::kPoses;
    case Step::kVotes:
      return GncExchange::kVotes;
    case Step::kWeights:
      return GncExchange::kWeights;
    case Step::kRejected:
      return GncExchange::kRejected;
    case Step::kReadmitted:
      return GncExchange::kReadmitted;
    case Step::kKeptStart:
      // Agent 0 gathers the kept values; the others wait for its start.
      return in_.id == 0 ? GncExchange::kKeptValues : GncExchange::kKeptStart;
    case Step::kCandidatePoses:
      return GncExchange::kCandidatePoses;
    case Step::kCandidateVotes:
      return GncExchange::kCandidateVotes;
    case Step::kPcm:
      return in_.id == 0 ? GncExchange::kPcmValues : GncExchange::kPcmDropped;
    case Step::kStartPoses:
      return GncExchange::kStartPoses;
    case Step::kStartVotes:
      return GncExchange::kStartVotes;
    default:  // not an exchange: begin_exchange() is never called with it
      throw std::logic_error("GncAgent: no exchange at this step");
  }
}

void GncAgent::take_exchange(std::vector<OutgoingMessage>& out) {
  std::optional<std::vector<ProtocolMessage>> ready = mail_->take_exchange();
  if (!ready) return;
  // Read into the book, or the agent's own data the exchange changes.
  for (const ProtocolMessage& m : *ready)
    if (!(step_ == Step::kPoses && stage_->poses_early_stale()))
      exchange_->read(exchange(), m,
                      GncExchangeTargets{weights_, zero_cut_, low_weights_, rejected_, *recheck_,
                                         stage_->iterate().rows()});
  after_exchange(out);
}

}  // namespace tessera
