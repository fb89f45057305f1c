#include "robust/gnc_exchange.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tessera/distributed/message_gate.hpp>

#include "distributed/measurement_block.hpp"
#include "distributed/pose_block_codec.hpp"
#include "robust/gnc_messages.hpp"

namespace tessera {

namespace {

std::vector<int> as_ints(const std::vector<std::uint32_t>& ids) {
  return {ids.begin(), ids.end()};
}

}  // namespace

std::pair<double, double> GncExchangeBook::summed_votes() const {
  std::pair<double, double> sum{0, 0};
  for (const auto& [sender, v] : votes_) {  // agent-id order: the same sums on every agent
    sum.first += v.first;
    sum.second += v.second;
  }
  return sum;
}

double GncExchangeBook::summed_near_bound() const {
  double sum = 0;
  for (const auto& [sender, v] : near_bound_) sum += v;  // agent-id order
  return sum;
}

double GncExchangeBook::summed_kept_cost() const {
  double sum = 0;
  for (const auto& [sender, v] : kept_costs_) sum += v;  // agent-id order
  return sum;
}

double GncExchangeBook::largest_vote() const {
  double max_r2 = 0;
  for (const auto& [sender, v] : votes_) max_r2 = std::max(max_r2, v.first);
  return max_r2;
}

void GncExchangeBook::expect_poses(Eigen::Index rows, bool both_starts) {
  neighbours_ = Eigen::MatrixXd::Zero(
      rows, (in_.d + 1) * static_cast<Eigen::Index>(terms_.neighbours().size()));
  if (both_starts) candidate_neighbours_ = neighbours_;
}

Eigen::MatrixXd GncExchangeBook::neighbours_at(const std::vector<std::size_t>& poses) const {
  const std::vector<std::size_t>& book = terms_.neighbours();  // sorted
  const Eigen::Index w = in_.d + 1;
  Eigen::MatrixXd out(neighbours_.rows(), w * static_cast<Eigen::Index>(poses.size()));
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto it = std::lower_bound(book.begin(), book.end(), poses[k]);
    if (it == book.end() || *it != poses[k])
      throw std::logic_error("GncExchangeBook: pose " + std::to_string(poses[k]) +
                             " is no neighbour pose of agent " + std::to_string(in_.id));
    out.middleCols(w * static_cast<Eigen::Index>(k), w) =
        neighbours_.middleCols(w * static_cast<Eigen::Index>(it - book.begin()), w);
  }
  return out;
}

void GncExchangeBook::publish(const Eigen::MatrixXd& Y, BlockKind kind, std::uint32_t phase,
                              std::vector<OutgoingMessage>& out, std::uint32_t round) const {
  const auto& adjacent = base_.adjacent[static_cast<std::size_t>(in_.id)];
  for (std::size_t q = 0; q < adjacent.size(); ++q) {
    const auto to_agent = static_cast<std::uint32_t>(adjacent[q]);
    out.push_back(OutgoingMessage{
        encode_public_poses(base_, in_.id, q, in_.d, Y, kind, round, phase), false, {to_agent}});
  }
}

std::vector<int> GncExchangeBook::gather_values_at_lead(std::uint32_t phase,
                                                        const std::vector<std::uint64_t>* rejected,
                                                        std::vector<OutgoingMessage>& out) {
  if (in_.id != 0) {
    out.push_back(OutgoingMessage{owned_values_block(in_, terms_, rejected, phase), false, {0}});
    return {0};
  }
  kept_values_.clear();
  append_owned_values(in_, terms_, rejected, kept_values_);
  return as_ints(other_agents(0, in_.num_agents));
}

void GncExchangeBook::read(GncExchange e, const ProtocolMessage& message, GncExchangeTargets to) {
  const std::uint32_t sender = message_sender(message);
  // Each exchange's message kind, or an error naming what arrived where (gnc_messages).
  const char* const kStatusBelongs = "poses where a robust status belongs";
  switch (e) {
    case GncExchange::kPcmValues:
      decode_measurement_block(
          expect_pose_block(message, in_.id, "a status where measurements belong"), in_.d,
          in_.num_poses, "robust pcm-gnc", kept_values_);
      break;
    case GncExchange::kPcmDropped:
      pcm_dropped_ = expect_status(message, in_.id, "poses where the consistency check belongs")
                         .measurement_ids;
      break;
    case GncExchange::kKeptValues:
      decode_measurement_block(
          expect_pose_block(message, in_.id, "a status where the kept set's start belongs"), in_.d,
          in_.num_poses, "robust solve", kept_values_);
      break;
    case GncExchange::kKeptStart:  // agent 0's fresh start of the kept set: this agent's block
      // With it, its cost over the kept set (RobustOptions::kept_vote_rides_weights).
      if (const auto* st = std::get_if<RoundStatusMessage>(&message)) {
        candidate_cost_ = st->cost;
        break;
      }
      candidate_ = read_kept_start(
          expect_pose_block(message, in_.id, "a status where the kept set's start belongs"),
          base_.poses[static_cast<std::size_t>(in_.id)], to.rank, in_.d, in_.id,
          terms_.neighbours(), candidate_neighbours_);
      break;
    case GncExchange::kPoses:
    case GncExchange::kPassTrialPoses:
    case GncExchange::kCandidatePoses:
    case GncExchange::kStartPoses: {
      const PoseBlockMessage& block = expect_pose_block(
          message, in_.id,
          "a status where robust poses from agent " + std::to_string(sender) + " belong");
      decode_neighbour_poses(block, terms_.neighbours(), in_.d, in_.id,
                             block.kind == BlockKind::kP ? candidate_neighbours_ : neighbours_);
      break;
    }
    case GncExchange::kVotes:
      votes_[sender] = {expect_status(message, in_.id, kStatusBelongs).cost, 0};
      break;
    case GncExchange::kCandidateVotes:
    case GncExchange::kStartVotes:
      votes_[sender] = read_vote(expect_status(message, in_.id, kStatusBelongs));
      break;
    case GncExchange::kTrialWeights:  // the same message, sent beside a trial's sums
    case GncExchange::kWeights: {
      if (const auto* block = std::get_if<PoseBlockMessage>(&message)) {  // agent 0: the values
        decode_measurement_block(*block, in_.d, in_.num_poses, "robust solve", held_values_);
        break;
      }
      const RoundStatusMessage& st = expect_status(message, in_.id, kStatusBelongs);
      votes_[sender] = {st.grad_norm_sq, st.cost};
      near_bound_[sender] = st.near_bound;
      kept_costs_[sender] = st.block_grad_norm;
      read_weights_message(st, sender, in_, to.weights, to.zero_cut, to.low_weights);
      break;
    }
    case GncExchange::kRejected: {
      const RoundStatusMessage& st = expect_status(message, in_.id, kStatusBelongs);
      to.rejected.insert(to.rejected.end(), st.measurement_ids.begin(), st.measurement_ids.end());
      break;
    }
    case GncExchange::kReadmitted: {
      const RoundStatusMessage& st = expect_status(message, in_.id, kStatusBelongs);
      read_readmitted_message(st, sender, in_.id, to.recheck);
      votes_[sender] = {st.cost, 0};
      break;
    }
  }
}

}  // namespace tessera
