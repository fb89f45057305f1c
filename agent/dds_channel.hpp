#pragma once
// The ProtocolChannel of the DDS runtime: core ProtocolMessages over a transport Session.
// A ROLLBACK order of the coordinator (newer epoch than this process's) interrupts a wait
// with RollbackRequested.

#include <optional>

#include "agent/round_loop.hpp"
#include "transport/session.hpp"

namespace tessera::agent {

class DdsProtocolChannel : public ProtocolChannel {
 public:
  explicit DdsProtocolChannel(transport::Session& session) : session_(session) {}
  void send(const OutgoingMessage& message) override;
  std::optional<ProtocolMessage> receive(double timeout_s) override;

 private:
  transport::Session& session_;
};

/// Takes the coordinator's newest ROLLBACK order with an epoch above the session's (older
/// ones are discarded), if any.
std::optional<RollbackRequested> take_rollback(transport::Session& session);

}  // namespace tessera::agent
