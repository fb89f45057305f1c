#pragma once
// Routing of received round-protocol messages by rollback epoch and protocol id. Every
// protocol message carries its sender's epoch: one of the current epoch addressed to this
// agent's current protocol id (and not sent by it) goes into the protocol inbox, one of an
// older epoch is dropped, one of a newer epoch is held until this process reaches that epoch
// (only then is it known whether it is for this agent: a re-partition for survivors
// renumbers the protocol ids). Internal to transport/ (Session::set_epoch is the public view).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <tessera/protocol/awaited_messages.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

#include "transport/inbox.hpp"

namespace tessera::transport {

class EpochRouter {
 public:
  /// Starts at epoch 0 with `protocol_id` (the agent id); delivers into `inbox`.
  EpochRouter(Mailroom& room, Inbox<ProtocolMessage>& inbox, std::uint32_t protocol_id);

  std::uint32_t epoch() const;
  /// epoch() for a caller that holds the mailroom lock.
  std::uint32_t epoch_locked() const { return epoch_; }
  std::uint32_t protocol_id() const;
  /// Moves to `epoch` with `protocol_id` (ignored if `epoch` is older than the current one):
  /// drops every queued protocol message (all of older epochs) and releases the held ones of
  /// `epoch` addressed to `protocol_id`. Wakes waiters.
  void set_epoch(std::uint32_t epoch, std::uint32_t protocol_id);
  /// A received message sent in epoch `epoch` by protocol id `sender` to `recipients` (or
  /// everyone when `broadcast`): delivered, held or dropped as above.
  /// Returns whether it woke the waiters.
  bool deliver(std::uint32_t epoch, std::uint32_t sender, bool broadcast,
               const std::vector<std::uint32_t>& recipients, ProtocolMessage&& message);
  /// deliver() wakes the waiters only once the inbox holds at least `n` messages (0 counts
  /// as 1). set_epoch() always wakes them.
  void set_wake_threshold(std::size_t n);
  /// While set, deliver() wakes the waiters only once the inbox holds a message of every
  /// awaited sender (the threshold is then ignored); nullopt goes back to the threshold.
  /// Wakes the waiters when the awaited messages are already queued.
  void set_awaited(std::optional<AwaitedMessages> awaited);
  /// Whether the inbox holds what the waiter needs: every awaited message when set, else any
  /// message. Requires the mailroom lock.
  bool ready_locked() const;

 private:
  struct Held {
    std::uint32_t epoch, sender;
    bool broadcast;
    std::vector<std::uint32_t> recipients;
    ProtocolMessage message;
  };

  Mailroom& room_;
  Inbox<ProtocolMessage>& inbox_;
  // Guarded by room_.mutex().
  std::uint32_t epoch_ = 0;
  std::uint32_t protocol_id_ = 0;
  std::size_t wake_threshold_ = 1;
  std::optional<AwaitedMessages> awaited_;
  std::vector<Held> future_;  // newer epochs' messages, with their routing
};

}  // namespace tessera::transport
