#include <cmath>
#include <stdexcept>
#include <tessera/distributed/saddle_escape.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/util/input_error.hpp>

#include "distributed/public_pose_messages.hpp"

namespace tessera {

void SaddleEscapeOptions::validate() const {
  if (max_trials <= 0) throw InputError("SaddleEscapeOptions.max_trials must be > 0");
}

SaddleEscapeProtocol::SaddleEscapeProtocol(const AgentState& state, const BlockLayout& layout,
                                           const Eigen::MatrixXd& direction, double cost,
                                           double grad_tol, const SaddleEscapeOptions& options)
    : state_(state),
      layout_(layout),
      problem_(state.problem()),
      f0_(cost),
      grad_tol_(grad_tol),
      options_(options) {
  options_.validate();
  if (direction.rows() != 1 || direction.cols() != state.Y.cols())
    throw std::invalid_argument("SaddleEscapeProtocol: direction has the wrong size");
  Ya_ = pad_rank(state.Y, 1);
  dir_ = Eigen::MatrixXd::Zero(Ya_.rows(), Ya_.cols());
  dir_.row(Ya_.rows() - 1) = direction;  // tangent at [Y; 0]: its last row is zero
  const double n = static_cast<double>(layout.owner.size());
  alpha_ = 1e2 * std::sqrt(n);
}

std::vector<OutgoingMessage> SaddleEscapeProtocol::start() {
  std::vector<OutgoingMessage> out;
  trial(out);
  pump(out);
  return out;
}

void SaddleEscapeProtocol::trial(std::vector<OutgoingMessage>& out) {
  Xp_ = problem_.manifold(static_cast<int>(Ya_.rows())).retract(Ya_, alpha_ * dir_);
  const auto& adj = layout_.adjacent[static_cast<std::size_t>(state_.id())];
  send_public_poses(state_, Xp_, BlockKind::kY, adj, trial_, kPoses, out);
  gate_.expect(trial_, kPoses, adj);
}

std::vector<OutgoingMessage> SaddleEscapeProtocol::handle(const ProtocolMessage& message) {
  const std::uint32_t sender = message_sender(message);
  const std::uint32_t step = message_phase(message);
  if (sender >= static_cast<std::uint32_t>(layout_.num_blocks) ||
      (step != kPoses && step != kStatus))
    throw std::runtime_error("saddle escape: agent " + std::to_string(state_.id()) +
                             ": malformed message (sender " + std::to_string(sender) + ", step " +
                             std::to_string(step) + ")");
  if (!gate_.add(static_cast<int>(sender), message_round(message), step, message))
    throw std::runtime_error("saddle escape: agent " + std::to_string(state_.id()) +
                             ": duplicate message from agent " + std::to_string(sender));
  std::vector<OutgoingMessage> out;
  pump(out);
  return out;
}

void SaddleEscapeProtocol::pump(std::vector<OutgoingMessage>& out) {
  while (!done_) {
    std::optional<MessageGate::Inbox> ready = gate_.take_ready();
    if (!ready) return;
    if (gate_.step() == kPoses) {
      Xpn_ = Eigen::MatrixXd::Zero(
          Ya_.rows(), (problem_.dim() + 1) * static_cast<Eigen::Index>(problem_.num_neighbors()));
      for (const auto& [sender, m] : *ready) state_.absorb(std::get<PoseBlockMessage>(m), Xpn_);
      if (problem_.num_neighbors() > 0) problem_.set_neighbor_poses(Xpn_);
      const double share = problem_.cost_share(Xp_);
      const double gsq =
          problem_.riemannian_gradient(Xp_, problem_.euclidean_gradient(Xp_)).squaredNorm();
      PoseBlockMessage m = make_reduction_message(state_.id(), trial_, kStatus, {share, gsq});
      gate_.add(state_.id(), trial_, kStatus, m);
      out.push_back(OutgoingMessage{std::move(m), true, {}});
      std::vector<int> all(static_cast<std::size_t>(layout_.num_blocks));
      for (int b = 0; b < layout_.num_blocks; ++b) all[static_cast<std::size_t>(b)] = b;
      gate_.expect(trial_, kStatus, std::move(all));
      continue;
    }
    const std::vector<double> t = reduce_in_id_order(*ready, 2);
    ++trial_;
    result_.trials = static_cast<int>(trial_);
    const double g = std::sqrt(std::max(0.0, t[1]));
    if (t[0] < f0_ && g > grad_tol_) {
      result_.success = true;
      result_.alpha = alpha_;
      result_.cost = t[0];
      result_.grad_norm = g;
      result_.Y = Xp_;
      result_.Yn = Xpn_;
      done_ = true;
      return;
    }
    if (static_cast<int>(trial_) >= options_.max_trials) {
      done_ = true;
      return;
    }
    alpha_ *= 0.5;
    trial(out);
  }
}

}  // namespace tessera
