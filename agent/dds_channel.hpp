#pragma once
// The ProtocolChannel of the DDS runtime: core ProtocolMessages over a transport Session.

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

}  // namespace tessera::agent
