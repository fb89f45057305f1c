#pragma once
// The agent's message routing around core's protocol: protocol messages go to the running
// protocol at once; rounding messages (which a faster agent may send before this one has
// finished its solve) are kept until the distributed rounding asks for them. It also times
// the waits and the sends and counts the certificate and escape traffic this agent sends.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <tessera/distributed/agent_process.hpp>
#include <tessera/distributed/stage_tag.hpp>
#include <utility>
#include <variant>
#include <vector>

#include "runtime/round_loop.hpp"
#include "runtime/stage_progress.hpp"

namespace tessera::agent {

/// One per agent and run; `channel` must outlive it. Every wait is bounded by `timeout_s`.
class Mailbox {
 public:
  Mailbox(ProtocolChannel& channel, double timeout_s, std::uint32_t self)
      : channel_(channel), timeout_s_(timeout_s), self_(self) {}

  /// Sends each message through the channel; adds the bytes of certificate and escape
  /// messages (per delivery, as the in-process driver counts them) to the counters below.
  void send_all(const std::vector<OutgoingMessage>& out);

  /// The next message from the channel, or nullopt after the receive timeout; the wait is
  /// added to wait_s. `wake_after`: see ProtocolChannel::receive_after.
  std::optional<ProtocolMessage> receive(std::size_t wake_after = 1);
  /// Same, sleeping until every awaited message has come (ProtocolChannel::receive_awaiting).
  std::optional<ProtocolMessage> receive(const AwaitedMessages& awaited);

  /// Agents in the run (for counting a broadcast's deliveries); 1 until set.
  void set_num_agents(std::uint32_t n) { num_agents_ = n; }

  /// Sends `first`, then feeds every protocol message to `protocol` and sends its replies
  /// until it is done; rounding messages that arrive meanwhile are kept for gather().
  /// Throws std::runtime_error naming this agent and describe() (where it is) when no
  /// message arrives within the timeout.
  template <class Describe>
  void run_protocol(AgentProcess& protocol, std::vector<OutgoingMessage> first, Describe describe) {
    send_all(first);
    while (!protocol.done()) {
      // Sleep until the current step can move on, not once per arriving message: a status
      // step needs every other agent's status, and each wake-up of this thread costs more
      // than handling a small message (docs/dds-runtime.md, "Round waits"). By name when
      // the protocol can tell: a count also counts messages of later steps.
      const std::optional<AwaitedMessages> awaited = protocol.awaited();
      std::optional<ProtocolMessage> msg =
          awaited ? receive(*awaited) : receive(protocol.messages_needed());
      if (!msg)
        throw std::runtime_error("agent " + std::to_string(self_) + ": no message for " +
                                 std::to_string(timeout_s_) + " s in " + describe());
      if (is_auxiliary_phase(phase_of(*msg))) {
        keep(std::move(*msg));
        continue;
      }
      send_all(protocol.handle(*msg));
      if (after_handled) after_handled();
    }
  }

  /// Called in run_protocol() after each message the protocol handled (agent 0's progress
  /// reports during the certificate and the Newton refinement); may be empty.
  std::function<void()> after_handled;

  /// Called on every agent at each progress point of a stage after the rounds (before the
  /// report below); may be empty (RoundLoopHooks::on_progress_point).
  std::function<void(ProgressStage)> on_progress_point;

  /// Agent 0's progress report of a stage after the rounds (runtime/stage_progress.hpp); on
  /// the other agents it does nothing.
  void report_progress(ProgressStage stage, std::uint64_t iteration, double value) {
    if (on_progress_point) on_progress_point(stage);
    if (!progress_) progress_.emplace(self_ == 0, channel_);
    progress_->report(stage, iteration, value);
  }

  /// Waits for the rounding messages of (phase, round) from every agent in `senders` and
  /// returns them by sender (ascending, so reductions sum in agent-id order); late protocol
  /// messages are dropped. Each wait asks the channel to sleep until as many messages as are
  /// still missing have come (ProtocolChannel::receive_after). Throws std::runtime_error naming the
  /// missing senders after the receive timeout.
  std::map<std::uint32_t, ProtocolMessage> gather(std::uint32_t phase, std::uint32_t round,
                                                  const std::vector<std::uint32_t>& senders);
  /// A gather counts as a message step (`gathers`) when this agent sent since the last one.
  /// This makes the next gather count though it did not: a gather at one agent, where the
  /// others' sends are the step.
  void next_gather_is_a_step() { sent_since_gather_ = true; }

 private:
  static std::uint32_t phase_of(const ProtocolMessage& m) {
    return std::visit([](const auto& x) { return x.phase; }, m);
  }
  static std::uint32_t round_of(const ProtocolMessage& m) {
    return std::visit([](const auto& x) { return x.round; }, m);
  }
  static std::uint32_t sender_of(const ProtocolMessage& m) {
    return std::visit([](const auto& x) { return x.sender; }, m);
  }
  void keep(ProtocolMessage m);

  ProtocolChannel& channel_;
  double timeout_s_;
  std::uint32_t self_;
  std::uint32_t num_agents_ = 1;
  bool sent_since_gather_ = false;
  std::optional<StageProgress> progress_;

 public:
  std::uint64_t certificate_bytes = 0, escape_bytes = 0;  // sent by this agent
  double wait_s = 0.0, send_s = 0.0;                      // time in receive() and in send_all()
  std::uint32_t gathers = 0;  // completed gather() steps (the rounding's message steps)

 private:
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::map<std::uint32_t, ProtocolMessage>>
      stash_;
};

}  // namespace tessera::agent
