#pragma once
// Where one GNC agent's incoming messages go; GncAgent decides the steps. A message of the
// running solve goes to it at once (its own protocol orders them). An exchange's messages wait
// in a MessageGate until every sender's is in and are then read in agent-id order, so every
// agent sums the same values in the same order. Messages of later steps (from faster agents)
// wait in the gate; those of a step this agent has left are of no use and dropped.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <tessera/distributed/message_gate.hpp>
#include <tessera/protocol/awaited_messages.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

namespace tessera {

class GncMailbox {
 public:
  explicit GncMailbox(int id) : id_(id) {}

  /// The solve of GNC step g runs from now on: returns its messages that came early (ordered
  /// by phase, round, sender; phases as on the wire).
  std::vector<ProtocolMessage> begin_solve(std::uint32_t g);
  /// The exchange of `phase` (gnc_phase()) from now on: one message from each of `senders`;
  /// both starts' poses (GncExchange::kStartPoses, kCandidatePoses) two, kind Y and kind P; with
  /// `values_too` (the first GncExchange::kWeights at agent 0), a status and a block of measurement
  /// values, or (GncExchange::kKeptStart) agent 0's start and a status with its cost.
  void begin_exchange(std::uint32_t phase, std::vector<int> senders, bool values_too = false);
  /// The exchange of an inlier pass's trial poses (GncExchange::kPassTrialPoses) of trial
  /// `trial` (the wire's round): one message from each of `senders`.
  void begin_trial_exchange(std::uint32_t phase, std::uint32_t trial, std::vector<int> senders);

  /// True when `m` is the running solve's (the caller hands it over); otherwise it waits for
  /// its step, or is dropped when of a step left. Throws std::runtime_error on a message the
  /// current exchange does not expect, or a second copy of one.
  bool add(const ProtocolMessage& m);
  /// Once every message of the current exchange is in: all of them (kind Y before kind P, each
  /// part in agent-id order), removed; nothing more until the next begin_*. Else nullopt.
  std::optional<std::vector<ProtocolMessage>> take_exchange();

  /// Drops the messages of the exchange of `phase` that came already: one that will not be
  /// waited for (one that comes later waits in the gate unread, and is dropped on arrival once
  /// this agent has left its step).
  void discard(std::uint32_t phase, std::uint32_t round = 0) { gate_.discard(round, phase); }
  /// The current exchange's missing messages (not during a solve: the solve names its own).
  std::size_t messages_needed() const;
  AwaitedMessages awaited() const;

 private:
  enum class Waiting { kSolve, kExchange, kNothing };
  bool is_current(std::uint32_t phase) const;
  std::uint32_t lowest_current_phase() const;
  // The gate's round: the inner solve's round, or the part of an exchange (the kind P blocks
  // of both starts' poses are part 1; an exchange's round on the wire is always 0).
  std::uint32_t gate_round(const ProtocolMessage& m) const;
  std::runtime_error unexpected(const ProtocolMessage& m) const;

  int id_;
  Waiting waiting_ = Waiting::kNothing;
  std::uint32_t g_ = 0;       // the running solve's GNC step
  std::uint32_t phase_ = 0;   // the current exchange's
  bool second_part_ = false;  // the current exchange has a part 1 (both starts, or values)
  MessageGate gate_;
  std::vector<ProtocolMessage> ready_;  // the exchange's first part, once all are in
};

}  // namespace tessera
