#pragma once
// Buffers one agent's incoming messages by (round, step) until the step it waits for has a
// message from every expected sender; the step then gets them ordered by sender id, so
// reductions sum in agent-id order and every agent takes bit-identical decisions. Messages of
// later steps (from faster agents) wait in the gate. A step is any 32-bit value, so a caller may
// key by a whole wire phase (the GNC agent's steps tag theirs far beyond a protocol's few steps).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <tessera/protocol/messages.hpp>
#include <vector>

namespace tessera {

class MessageGate {
 public:
  using Inbox = std::map<int, ProtocolMessage>;  // by sender

  /// From now on wait for step (round, step) from `senders`.
  void expect(std::uint32_t round, std::uint32_t step, std::vector<int> senders);
  /// Stores a message; false when the same (round, step, sender) was already stored.
  bool add(int sender, std::uint32_t round, std::uint32_t step, ProtocolMessage message);
  /// The expected step's messages once all are in (removed from the gate), else nullopt.
  std::optional<Inbox> take_ready();
  /// The expected step's senders whose message has not arrived yet, ascending.
  std::vector<int> missing() const;
  /// The expected step's senders, as given to expect().
  const std::vector<int>& senders() const { return senders_; }
  /// Every stored message of the steps [first, last), whatever its round, removed from the gate
  /// and ordered by step, round and sender: for a caller that forwards a whole stage to a
  /// protocol that waits for its own steps, instead of waiting for one step here.
  std::vector<ProtocolMessage> take_steps(std::uint32_t first, std::uint32_t last);
  /// Drops the stored messages of step (round, step): for a step that will not be waited for.
  void discard(std::uint32_t round, std::uint32_t step) { pending_.erase(key(round, step)); }
  std::uint32_t round() const { return round_; }
  std::uint32_t step() const { return step_; }

 private:
  static std::uint64_t key(std::uint32_t round, std::uint32_t step) {
    return (static_cast<std::uint64_t>(round) << 32) | step;
  }
  static std::uint32_t step_of(std::uint64_t key) { return static_cast<std::uint32_t>(key); }
  std::map<std::uint64_t, Inbox> pending_;
  std::uint32_t round_ = 0, step_ = 0;
  std::vector<int> senders_;
};

/// A global reduction's contribution travels as a PoseBlockMessage broadcast whose "poses"
/// 0..k-1 are k scalars (rank 1, dim 0), so every transport that carries pose blocks carries it.
PoseBlockMessage make_reduction_message(int sender, std::uint32_t round, std::uint32_t phase,
                                        const std::vector<double>& values);
/// The values of a reduction message; throws std::runtime_error naming the sender when the
/// message does not hold exactly `count` values.
const std::vector<double>& reduction_values(const ProtocolMessage& message, std::size_t count);

/// Sums the contributions of every sender in id order (the inbox's order): entry k summed,
/// except entries listed in `max_entries`, which take the maximum.
std::vector<double> reduce_in_id_order(const MessageGate::Inbox& inbox, std::size_t count,
                                       const std::vector<std::size_t>& max_entries = {});

/// round, sender and phase of any protocol message.
std::uint32_t message_round(const ProtocolMessage& m);
std::uint32_t message_sender(const ProtocolMessage& m);
std::uint32_t message_phase(const ProtocolMessage& m);

}  // namespace tessera
