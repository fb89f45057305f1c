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

void EpochRouter::deliver(std::uint32_t e, std::uint32_t sender, bool broadcast,
                          const std::vector<std::uint32_t>& recipients, ProtocolMessage&& m) {
  bool wake = false;
  room_.with_lock([&] {
    if (e == epoch_) {
      if (sender != protocol_id_ && addressed_to(broadcast, recipients, protocol_id_)) {
        inbox_.push_locked(std::move(m));
        wake = !consumed_ && inbox_.queued_locked().size() >= wake_threshold_;
      }
    } else if (e > epoch_) {
      future_.push_back(Held{e, sender, broadcast, recipients, std::move(m)});
    }
    return 0;
  });
  if (wake) room_.notify();
}

void EpochRouter::set_consumer(std::function<void()> consumer) {
  std::lock_guard<std::mutex> calls(consumer_mutex_);
  room_.with_lock([&] { return consumed_ = static_cast<bool>(consumer); });
  consumer_ = std::move(consumer);
}

void EpochRouter::hand_over() {
  consume_again_.store(true);
  for (;;) {
    std::unique_lock<std::mutex> calls(consumer_mutex_, std::try_to_lock);
    if (!calls.owns_lock()) return;  // the holder sees consume_again_ before letting go
    while (consume_again_.exchange(false))
      if (consumer_) consumer_();
    calls.unlock();
    // A caller may have set the flag after our last look and found the mutex still taken.
    if (!consume_again_.load()) return;
  }
}

}  // namespace tessera::transport
