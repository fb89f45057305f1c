#include "robust/gnc_mailbox.hpp"

#include <algorithm>
#include <string>
#include <tessera/robust/gnc_agent.hpp>
#include <utility>

namespace tessera {

namespace {

// An inlier pass's trial poses: the one exchange whose wire round is not 0 (the trial's number).
bool pass_trial(std::uint32_t phase) {
  return phase % kGncStepStride ==
         kGncExchangeBase + static_cast<std::uint32_t>(GncExchange::kPassTrialPoses);
}

// The exchanges that carry two blocks per neighbour: both starts' poses (kind Y, kind P).
bool two_starts(std::uint32_t phase) {
  const std::uint32_t e = phase % kGncStepStride;
  return e == kGncExchangeBase + static_cast<std::uint32_t>(GncExchange::kStartPoses) ||
         e == kGncExchangeBase + static_cast<std::uint32_t>(GncExchange::kCandidatePoses);
}

}  // namespace

std::vector<ProtocolMessage> GncMailbox::begin_solve(std::uint32_t g) {
  waiting_ = Waiting::kSolve;
  g_ = g;
  ready_.clear();
  return gate_.take_steps(g * kGncStepStride, g * kGncStepStride + kGncExchangeBase);
}

void GncMailbox::begin_trial_exchange(std::uint32_t phase, std::uint32_t trial,
                                      std::vector<int> senders) {
  waiting_ = Waiting::kExchange;
  phase_ = phase;
  second_part_ = false;
  ready_.clear();
  gate_.expect(trial, phase, std::move(senders));
}

void GncMailbox::begin_exchange(std::uint32_t phase, std::vector<int> senders, bool values_too) {
  waiting_ = Waiting::kExchange;
  phase_ = phase;
  second_part_ = two_starts(phase) || values_too;
  ready_.clear();
  gate_.expect(0, phase, std::move(senders));
}

bool GncMailbox::is_current(std::uint32_t phase) const {
  switch (waiting_) {
    case Waiting::kSolve:
      return phase >= g_ * kGncStepStride && phase < g_ * kGncStepStride + kGncExchangeBase;
    case Waiting::kExchange:
      return phase == phase_;
    default:
      return false;
  }
}

std::uint32_t GncMailbox::lowest_current_phase() const {
  return waiting_ == Waiting::kSolve ? g_ * kGncStepStride : phase_;
}

std::uint32_t GncMailbox::gate_round(const ProtocolMessage& m) const {
  const std::uint32_t phase = message_phase(m);
  if (phase % kGncStepStride < kGncExchangeBase) return message_round(m);
  if (pass_trial(phase)) return message_round(m);  // the trial's number
  const auto* block = std::get_if<PoseBlockMessage>(&m);
  if (two_starts(phase)) return block && block->kind == BlockKind::kP ? 1 : 0;
  // Measurement values beside the first weights, and the start's cost beside agent 0's start of
  // the kept set (the wire's round stays 0: a runtime waits by it).
  const std::uint32_t weights =
      kGncExchangeBase + static_cast<std::uint32_t>(GncExchange::kWeights);
  const std::uint32_t kept_start =
      kGncExchangeBase + static_cast<std::uint32_t>(GncExchange::kKeptStart);
  if (phase % kGncStepStride == kept_start) return block ? 0 : 1;
  return block && phase % kGncStepStride == weights ? 1 : 0;
}

std::runtime_error GncMailbox::unexpected(const ProtocolMessage& m) const {
  return std::runtime_error("agent " + std::to_string(id_) + ": unexpected robust message " +
                            std::to_string(message_phase(m)) + " from agent " +
                            std::to_string(message_sender(m)));
}

bool GncMailbox::add(const ProtocolMessage& m) {
  const std::uint32_t phase = message_phase(m);
  if (phase < lowest_current_phase()) return false;  // a step this agent has left needs nothing
  const bool current = is_current(phase);
  if (current && waiting_ == Waiting::kSolve) return true;
  const auto sender = static_cast<int>(message_sender(m));
  const std::vector<int>& expected = gate_.senders();
  if (current && std::find(expected.begin(), expected.end(), sender) == expected.end())
    throw unexpected(m);
  if (!gate_.add(sender, gate_round(m), phase, m)) throw unexpected(m);
  return false;
}

std::optional<std::vector<ProtocolMessage>> GncMailbox::take_exchange() {
  while (waiting_ == Waiting::kExchange) {
    std::optional<MessageGate::Inbox> inbox = gate_.take_ready();
    if (!inbox) return std::nullopt;
    const std::vector<int>& expected = gate_.senders();
    for (auto& [sender, m] : *inbox) {
      if (std::find(expected.begin(), expected.end(), sender) == expected.end())
        throw unexpected(m);
      ready_.push_back(std::move(m));
    }
    if (second_part_ && gate_.round() == 0) {
      gate_.expect(1, phase_, expected);  // the kind P blocks (or values) from the same senders
      continue;
    }
    waiting_ = Waiting::kNothing;
    return std::move(ready_);
  }
  return std::nullopt;
}

std::size_t GncMailbox::messages_needed() const {
  return std::max<std::size_t>(gate_.missing().size(), 1);
}

AwaitedMessages GncMailbox::awaited() const {
  const std::vector<int> missing = gate_.missing();
  // The wire's round is 0 but for a pass's trial poses (their trial's number).
  return AwaitedMessages{
      pass_trial(phase_) ? gate_.round() : 0, phase_, {missing.begin(), missing.end()}};
}

}  // namespace tessera
