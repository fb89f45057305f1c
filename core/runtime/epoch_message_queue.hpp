#pragma once
// The protocol messages an online agent received and has not handled yet (the DDS side is
// agent/online_link.cpp). Every member solves each epoch's graph with the round protocol, and a
// faster member may start the next epoch's rounds while this one still solves: those messages
// wait for their solve. A message of an older epoch (a solve that ended, or an epoch abandoned
// at a take-over) and one addressed to other agents only are of no use here and go.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace tessera::runtime {

/// `Sample`: a received protocol message with its routing, fields `epoch`, `sender`,
/// `broadcast` and `recipients` (as transport::OnlineProtocolSample).
template <class Sample>
class EpochMessageQueue {
 public:
  void push(Sample s) { queue_.push_back(std::move(s)); }

  /// One pass over the queue in arrival order: every message of `epoch` from another block
  /// than `me` and addressed to it (or broadcast) goes to `handle`, while `done()` is false;
  /// later epochs' messages stay, the rest goes. Once `done()` holds, what was not looked at
  /// stays queued as it is. Returns whether a message was handled. The queue is compacted in
  /// place (no erase from its middle per message).
  template <class Handle, class Done>
  bool take(std::uint32_t epoch, std::uint32_t me, Handle&& handle, Done&& done) {
    bool handled = false;
    std::size_t keep = 0, k = 0;
    for (; k < queue_.size() && !done(); ++k) {
      Sample& m = queue_[k];
      if (addressed_to(m, epoch, me)) {
        handle(m);
        handled = true;
      } else if (m.epoch > epoch) {
        if (keep != k) queue_[keep] = std::move(m);
        ++keep;
      }
    }
    for (; k < queue_.size(); ++k, ++keep)
      if (keep != k) queue_[keep] = std::move(queue_[k]);
    queue_.erase(queue_.begin() + static_cast<std::ptrdiff_t>(keep), queue_.end());
    return handled;
  }

  /// Drops the messages of the epochs below `epoch` (abandoned at a take-over).
  void drop_before(std::uint32_t epoch) {
    queue_.erase(std::remove_if(queue_.begin(), queue_.end(),
                                [&](const Sample& m) { return m.epoch < epoch; }),
                 queue_.end());
  }

  std::size_t size() const { return queue_.size(); }

 private:
  static bool addressed_to(const Sample& m, std::uint32_t epoch, std::uint32_t me) {
    return m.epoch == epoch && m.sender != me &&
           (m.broadcast ||
            std::find(m.recipients.begin(), m.recipients.end(), me) != m.recipients.end());
  }

  std::vector<Sample> queue_;
};

}  // namespace tessera::runtime
