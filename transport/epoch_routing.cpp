#include "transport/epoch_routing.hpp"

#include "transport/message_mapping.hpp"

namespace tessera::transport {

EpochRouter::EpochRouter(Mailroom& room, Inbox<ProtocolMessage>& inbox, std::uint32_t protocol_id)
    : room_(room), inbox_(inbox), protocol_id_(protocol_id) {}

std::uint32_t EpochRouter::epoch() const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  return epoch_;
}

std::uint32_t EpochRouter::protocol_id() const {
  std::lock_guard<std::mutex> lock(room_.mutex());
  return protocol_id_;
}

void EpochRouter::set_epoch(std::uint32_t e, std::uint32_t protocol_id) {
  room_.with_lock([&] {
    if (e < epoch_) return 0;
    epoch_ = e;
    protocol_id_ = protocol_id;
    inbox_.clear_locked();  // everything queued is of an older epoch
    std::vector<Held> later;
    for (auto& h : future_) {
      if (h.epoch == e) {
        if (h.sender != protocol_id && addressed_to(h.broadcast, h.recipients, protocol_id))
          inbox_.push_locked(std::move(h.message));
      } else if (h.epoch > e) {
        later.push_back(std::move(h));
      }
    }
    future_ = std::move(later);
    return 0;
  });
  room_.notify();
}

void EpochRouter::set_wake_threshold(std::size_t n) {
  std::lock_guard<std::mutex> lock(room_.mutex());
  wake_threshold_ = n > 0 ? n : 1;
}

void EpochRouter::set_awaited(std::optional<AwaitedMessages> awaited) {
  const bool ready = room_.with_lock([&] {
    awaited_ = std::move(awaited);
    return awaited_ && ready_locked();
  });
  if (ready) room_.notify();
}

bool EpochRouter::ready_locked() const {
  const auto& queued = inbox_.queued_locked();
  return awaited_ ? all_awaited_in(*awaited_, queued) : !queued.empty();
}

bool EpochRouter::deliver(std::uint32_t e, std::uint32_t sender, bool broadcast,
                          const std::vector<std::uint32_t>& recipients, ProtocolMessage&& m) {
  bool wake = false;
  room_.with_lock([&] {
    if (e == epoch_) {
      if (sender != protocol_id_ && addressed_to(broadcast, recipients, protocol_id_)) {
        // Only a message the waiter awaits can complete its step; any other only queues.
        const bool counts = !awaited_ || is_awaited(*awaited_, m);
        inbox_.push_locked(std::move(m));
        wake = counts &&
               (awaited_ ? ready_locked() : inbox_.queued_locked().size() >= wake_threshold_);
      }
    } else if (e > epoch_) {
      future_.push_back(Held{e, sender, broadcast, recipients, std::move(m)});
    }
    return 0;
  });
  if (wake) room_.notify();
  return wake;
}

}  // namespace tessera::transport
