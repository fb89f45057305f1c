// GncAgent's opening steps, before the first solve: with pcm-gnc the pairwise consistency check
// at agent 0 and the closures it drops, with a second start (GncAgentInput::Y0_known) the vote
// between the two starts; then step 0 ends. The state machine after them is gnc_agent.cpp.

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/robust/gnc_agent.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>
#include <vector>

#include "robust/gnc_exchange.hpp"
#include "robust/gnc_lead_steps.hpp"
#include "robust/gnc_local_terms.hpp"
#include "robust/gnc_messages.hpp"
#include "robust/gnc_solve_stage.hpp"

namespace tessera {

std::vector<OutgoingMessage> GncAgent::start() {
  std::vector<OutgoingMessage> out;
  if (in_.pcm) {
    if (!terms_->known_connected()) {
      const std::string why =
          "robust pcm-gnc: the known inliers do not connect the poses, so there is no odometry "
          "to test closures against (use --robust gnc-tls)";
      if (in_.source.empty()) throw InputError(why);
      throw InputError(in_.source, 0, why);
    }
    begin_exchange(Step::kPcm, out);
  } else if (in_.Y0_known.size() > 0) {
    begin_exchange(Step::kStartPoses, out);
  } else {
    begin_solve(out);
  }
  return out;
}

void GncAgent::after_pcm(std::vector<OutgoingMessage>& out) {
  if (in_.id == 0) {
    const std::vector<std::uint64_t> ids =
        inconsistent_closures(exchange_->kept_values(), in_, *terms_);
    RoundStatusMessage st;
    st.measurement_ids = ids;
    broadcast_status(std::move(st), 0, gnc_phase(g_, GncExchange::kPcmDropped), in_.num_agents,
                     out);
    drop_inconsistent(ids);
  } else {
    drop_inconsistent(exchange_->pcm_dropped());
  }
  if (in_.Y0_known.size() > 0)
    begin_exchange(Step::kStartPoses, out);
  else
    after_step_zero(false, out);
}

void GncAgent::drop_inconsistent(const std::vector<std::uint64_t>& ids) {
  // Weight 0 from the start, never re-weighted (the inlier passes may take them back).
  zero_cut_.clear();
  for (std::uint64_t id : ids) {
    if (id >= in_.structure.size())
      throw std::runtime_error("robust pcm-gnc: measurement " + std::to_string(id) +
                               " out of range");
    if (const auto k = position_of(in_.measurement_index, id)) {
      dropped_[*k] = true;
      weights_[*k] = 0.0;
    }
    const auto& [i, j] = in_.structure[id];
    if (in_.owner[i] != in_.owner[j]) zero_cut_.push_back(id);
  }
  // They leave the solves (the known inliers connect the poses): the layout without them.
  std::sort(zero_cut_.begin(), zero_cut_.end());
  solve_without(zero_cut_);
}

void GncAgent::after_start_votes(std::vector<OutgoingMessage>& out) {
  const auto [at_start, at_known] = exchange_->summed_votes();
  const bool known = at_known < at_start;
  if (known) stage_->set_start(std::move(in_.Y0_known));
  in_.Y0_known.resize(0, 0);
  // RobustOptions::first_solve_takes_start_poses: the winner's neighbour poses came with the
  // vote's pose exchange (the same on every agent: the option and the summed votes).
  if (options_.robust.first_solve_takes_start_poses) {
    if (known) exchange_->adopt_candidate_neighbours();
    neighbours_current_ = true;
  }
  exchange_->forget_candidate_neighbours();
  after_step_zero(true, out);
}

void GncAgent::after_step_zero(bool start_voted, std::vector<OutgoingMessage>& out) {
  first_solve_g_ = ++g_;
  if (start_voted && weighs_at_start()) {
    // RobustOptions::weigh_at_start: mu's start and the first weights at the voted start, the
    // step the first solve would have had (its exchanges' tags are the same).
    begin_exchange(neighbours_current_ ? Step::kVotes : Step::kPoses, out);
    return;
  }
  begin_solve(out);
}

bool GncAgent::weighs_at_start() const {
  // Every agent decides the same: the option and the weighted solves' layout (Newton steps
  // where the interface fits: near-minimisers of each weighted problem; by rounds, weighed at
  // the start, manhattan3500 with 25 % random outliers kept a wrong closure).
  return options_.robust.weigh_at_start && stage_->gnc_refines();
}

}  // namespace tessera
