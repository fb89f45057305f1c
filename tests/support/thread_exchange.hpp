#pragma once
// An in-memory stand-in for the DDS transport: N agents in threads of one process, each with a
// queue; a channel posts a message into its recipients' queues (never back to the sender), in
// the order sent. Used by the tests and benches that run core's agent stages without DDS.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <vector>

#include "runtime/round_loop.hpp"

namespace tessera::test {

class ThreadExchange {
 public:
  explicit ThreadExchange(std::uint32_t n) : queues_(n) {}
  std::uint32_t size() const { return static_cast<std::uint32_t>(queues_.size()); }
  /// Copies m.message into the queue of every recipient of `m` other than `from`.
  void post(std::uint32_t from, const OutgoingMessage& m);
  /// The oldest message for `self`, or nullopt after `timeout_s` seconds without one.
  std::optional<ProtocolMessage> take(std::uint32_t self, double timeout_s);
  /// Messages posted and not taken yet, over every queue.
  std::size_t left_over();

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<std::deque<ProtocolMessage>> queues_;
};

/// Agent `self`'s channel over a ThreadExchange (which must outlive it).
class ThreadChannel : public agent::ProtocolChannel {
 public:
  ThreadChannel(ThreadExchange& ex, std::uint32_t self) : ex_(ex), self_(self) {}
  void send(const OutgoingMessage& m) override { ex_.post(self_, m); }
  std::optional<ProtocolMessage> receive(double timeout_s) override {
    return ex_.take(self_, timeout_s);
  }

 private:
  ThreadExchange& ex_;
  std::uint32_t self_;
};

}  // namespace tessera::test
