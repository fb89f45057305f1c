#include "agent/dds_channel.hpp"

namespace tessera::agent {

void DdsProtocolChannel::send(const OutgoingMessage& message) {
  if (auto stop = session_.mailroom().stop_info()) throw RunStopped(stop->reason);
  session_.send(message);
}

std::optional<RollbackRequested> take_rollback(transport::Session& session) {
  const std::uint32_t current = session.epoch();
  std::optional<RollbackRequested> newest;
  for (const auto& c : session.rollbacks().take_all())
    if (c.epoch() > current && (!newest || c.epoch() > newest->epoch))
      newest = RollbackRequested(c.round(), c.epoch(), c.agent());
  return newest;
}

std::optional<ProtocolMessage> DdsProtocolChannel::receive(double timeout_s) {
  const std::uint32_t current = session_.epoch();
  auto& rollbacks = session_.rollbacks();
  auto& protocol = session_.protocol();
  const transport::WaitStatus st = session_.mailroom().wait_for(
      [&] {
        for (const auto& c : rollbacks.queued_locked())
          if (c.epoch() > current) return true;
        return !protocol.queued_locked().empty();
      },
      transport::Seconds(timeout_s));
  if (st == transport::WaitStatus::kStopped)
    throw RunStopped(session_.mailroom().stop_info()->reason);
  if (st == transport::WaitStatus::kTimeout) return std::nullopt;
  if (auto r = take_rollback(session_)) throw *r;
  ProtocolMessage out;
  if (protocol.take(transport::Seconds(0), &out) == transport::WaitStatus::kReady) return out;
  return std::nullopt;  // only stale rollbacks were queued; the caller waits again
}

}  // namespace tessera::agent
