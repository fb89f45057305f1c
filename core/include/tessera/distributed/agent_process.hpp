#pragma once
// What a driver (the in-process driver, the DDS round loop) needs from one agent: a state
// machine that emits messages when started and consumes one message at a time. RoundProtocol
// is one; the certified sequence (solve -> certify -> escape -> solve ...) is another.

#include <cstddef>
#include <optional>
#include <tessera/protocol/awaited_messages.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

namespace tessera {

class AgentProcess {
 public:
  virtual ~AgentProcess() = default;
  /// The first messages; called once before any handle().
  virtual std::vector<OutgoingMessage> start() = 0;
  /// Consumes one message addressed to this agent and returns what it wants sent.
  virtual std::vector<OutgoingMessage> handle(const ProtocolMessage& message) = 0;
  /// True once the agent needs no further message.
  virtual bool done() const = 0;
  /// How many more messages must arrive before handle() can move the current step on: a
  /// lower bound (1 when the agent cannot tell, 0 once done). A driver may sleep until that
  /// many have arrived instead of waking for each one; a wait for fewer is never wrong.
  virtual std::size_t messages_needed() const { return done() ? 0 : 1; }
  /// The messages the current step still lacks, by (round, phase, sender), when the agent can
  /// name them (messages_needed() of them); nullopt when it cannot or is done. A driver may
  /// sleep until exactly these have arrived: handle() cannot move the step on before.
  virtual std::optional<AwaitedMessages> awaited() const { return std::nullopt; }
};

}  // namespace tessera
