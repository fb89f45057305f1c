#include "agent/dds_channel.hpp"

namespace tessera::agent {

void DdsProtocolChannel::send(const OutgoingMessage& message) {
  if (auto stop = session_.mailroom().stop_info()) throw RunStopped(stop->reason);
  session_.send(message);
}

std::optional<ProtocolMessage> DdsProtocolChannel::receive(double timeout_s) {
  ProtocolMessage out;
  switch (session_.protocol().take(transport::Seconds(timeout_s), &out)) {
    case transport::WaitStatus::kReady:
      return out;
    case transport::WaitStatus::kTimeout:
      return std::nullopt;
    case transport::WaitStatus::kStopped:
      break;
  }
  throw RunStopped(session_.mailroom().stop_info()->reason);
}

}  // namespace tessera::agent
