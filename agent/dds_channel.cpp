#include "agent/dds_channel.hpp"

#include <algorithm>
#include <chrono>

#include "transport/transport_error.hpp"

namespace tessera::agent {

void DdsProtocolChannel::send(const OutgoingMessage& message) {
  if (auto stop = session_.mailroom().stop_info()) throw RunStopped(stop->reason);
  session_.send(message);
  note_status(message.message, true);
}

void DdsProtocolChannel::send_all(const std::vector<OutgoingMessage>& messages) {
  if (auto stop = session_.mailroom().stop_info()) throw RunStopped(stop->reason);
  session_.send_all(messages);
  for (const auto& m : messages) note_status(m.message, true);
}

void DdsProtocolChannel::report(const AgentReport& report) {
  if (auto stop = session_.mailroom().stop_info()) throw RunStopped(stop->reason);
  session_.report(report);
}

void DdsProtocolChannel::report_progress(std::uint32_t agent, std::uint32_t num_agents,
                                         ProgressDigestOptions options) {
  progress_.emplace(agent, num_agents, agent == 0, options, std::chrono::steady_clock::now());
}

void DdsProtocolChannel::publish_final_progress() {
  if (!progress_) return;
  wire::AgentProgress d = progress_->take(std::chrono::steady_clock::now(), true);
  d.epoch(session_.epoch());
  session_.publish(std::move(d));
}

void DdsProtocolChannel::note_status(const ProtocolMessage& m, bool own) {
  if (!progress_) return;
  if (const auto* status = std::get_if<RoundStatusMessage>(&m))
    progress_->on_status(*status, own, std::chrono::steady_clock::now());
  publish_progress_if_due();
}

void DdsProtocolChannel::publish_progress_if_due() {
  if (!progress_) return;
  const auto now = std::chrono::steady_clock::now();
  if (!progress_->due(now)) return;
  wire::AgentProgress d = progress_->take(now);
  d.epoch(session_.epoch());
  // A digest the coordinator has not taken in time is superseded by the next one: dropping it
  // loses no information, and must not stop the run (a 1M-pose run at load 40-55 stopped in its
  // rounding on one). A coordinator that is gone is noticed by its lease.
  try {
    session_.publish(std::move(d));
  } catch (const transport::TransportError&) {
  }
}

std::optional<RollbackRequested> take_rollback(transport::AgentSession& session) {
  const std::uint32_t current = session.epoch();
  std::optional<RollbackRequested> newest;
  for (const auto& c : session.rollbacks().take_all())
    if (c.epoch() > current && (!newest || c.epoch() > newest->epoch))
      newest = RollbackRequested(c.round(), c.epoch(), c.agent());
  return newest;
}

std::optional<wire::PartitionAssignment> take_reassignment(transport::AgentSession& session) {
  const std::uint32_t current = session.epoch();
  std::optional<wire::PartitionAssignment> newest;
  for (auto& a : session.assignments().take_all())
    if (a.epoch() > current && (!newest || a.epoch() > newest->epoch())) newest = std::move(a);
  return newest;
}

std::optional<ProtocolMessage> DdsProtocolChannel::receive(double timeout_s) {
  return receive_after(timeout_s, 1);
}

std::optional<ProtocolMessage> DdsProtocolChannel::receive_after(double timeout_s,
                                                                 std::size_t wake_after) {
  // Back to a wake-up per message however this wait ends: the threshold is this step's only.
  struct ThresholdGuard {
    transport::AgentSession& session;
    bool set;
    ~ThresholdGuard() {
      if (set) session.set_protocol_wake_threshold(1);
    }
  } guard{session_, wake_after > 1};
  if (guard.set) session_.set_protocol_wake_threshold(wake_after);
  return wait_and_take(timeout_s);
}

std::optional<ProtocolMessage> DdsProtocolChannel::receive_awaiting(
    double timeout_s, const AwaitedMessages& awaited) {
  // Messages this channel consumes itself (replicas) must wake it as they come: the
  // coordinator's re-partition drops whatever is still queued, and the replica of an agent
  // lost meanwhile with it. Only a count counts them (a step's wait names protocol messages).
  if (intercept_) return receive_after(timeout_s, awaited.senders.size());
  // Back to a wake-up per message however this wait ends: the awaited set is this step's only.
  struct AwaitedGuard {
    transport::AgentSession& session;
    ~AwaitedGuard() { session.set_protocol_awaited(std::nullopt); }
  } guard{session_};
  session_.set_protocol_awaited(awaited);
  return wait_and_take(timeout_s);
}

std::optional<ProtocolMessage> DdsProtocolChannel::wait_and_take(double timeout_s) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::duration<double>(timeout_s));
  for (;;) {
    const std::uint32_t current = session_.epoch();
    auto& rollbacks = session_.rollbacks();
    auto& assignments = session_.assignments();
    // A digest falls due while we wait (a slow peer): wake for it, then wait on.
    const auto until = progress_ ? std::min(deadline, progress_->next_due()) : deadline;
    const double left =
        std::chrono::duration<double>(until - std::chrono::steady_clock::now()).count();
    const transport::WaitStatus st = session_.mailroom().wait_for(
        [&] {
          for (const auto& c : rollbacks.queued_locked())
            if (c.epoch() > current) return true;
          for (const auto& a : assignments.queued_locked())
            if (a.epoch() > current) return true;
          return session_.protocol_ready_locked();
        },
        transport::Seconds(std::max(0.0, left)));
    if (st == transport::WaitStatus::kStopped)
      throw RunStopped(session_.mailroom().stop_info()->reason);
    // On the relay agent: the statuses that just woke us may complete a step the others
    // wait for; send its bundle before handling them (status_relay.hpp).
    session_.relay_statuses();
    if (st == transport::WaitStatus::kTimeout) {
      if (until == deadline) return std::nullopt;
      publish_progress_if_due();
      continue;
    }
    if (auto a = take_reassignment(session_)) throw RepartitionRequested(std::move(*a));
    if (auto r = take_rollback(session_)) throw *r;
    ProtocolMessage out;
    if (session_.protocol().take(transport::Seconds(0), &out) != transport::WaitStatus::kReady)
      return std::nullopt;  // only stale rollbacks were queued; the caller waits again
    if (intercept_ && intercept_(out)) continue;  // e.g. a replica, not for the protocol
    note_status(out, false);
    return out;
  }
}

}  // namespace tessera::agent
