#include "agent/dds_channel.hpp"

#include <algorithm>
#include <chrono>

namespace tessera::agent {

void DdsProtocolChannel::send(const OutgoingMessage& message) {
  if (auto stop = session_.mailroom().stop_info()) throw RunStopped(stop->reason);
  session_.send(message);
  note_status(message.message, true);
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
  session_.publish(std::move(d));
}

std::optional<RollbackRequested> take_rollback(transport::Session& session) {
  const std::uint32_t current = session.epoch();
  std::optional<RollbackRequested> newest;
  for (const auto& c : session.rollbacks().take_all())
    if (c.epoch() > current && (!newest || c.epoch() > newest->epoch))
      newest = RollbackRequested(c.round(), c.epoch(), c.agent());
  return newest;
}

std::optional<wire::PartitionAssignment> take_reassignment(transport::Session& session) {
  const std::uint32_t current = session.epoch();
  std::optional<wire::PartitionAssignment> newest;
  for (auto& a : session.assignments().take_all())
    if (a.epoch() > current && (!newest || a.epoch() > newest->epoch())) newest = std::move(a);
  return newest;
}

bool DdsProtocolChannel::interrupted_locked(std::uint32_t current) {
  for (const auto& c : session_.rollbacks().queued_locked())
    if (c.epoch() > current) return true;
  for (const auto& a : session_.assignments().queued_locked())
    if (a.epoch() > current) return true;
  return false;
}

void DdsProtocolChannel::consume(Driving& d) {
  transport::Mailroom& room = session_.mailroom();
  if (room.with_lock([&] { return d.finished; })) return;
  try {
    const std::uint32_t current = session_.epoch();
    // On the relay agent: the statuses just received may complete a step the others wait
    // for; send its bundle before handling them (status_relay.hpp).
    session_.relay_statuses();
    bool finished = false;
    while (!finished) {
      // Rollbacks, re-partitions and stops are for the waiting thread (they woke it).
      if (room.with_lock([&] { return interrupted_locked(current); })) break;
      ProtocolMessage m;
      if (session_.protocol().take(transport::Seconds(0), &m) != transport::WaitStatus::kReady)
        break;
      ++d.handled;
      if (intercept_ && intercept_(m)) continue;  // e.g. a replica, not for the protocol
      note_status(m, false);
      finished = d.step(std::move(m));
    }
    publish_progress_if_due();
    if (!finished) return;
  } catch (...) {
    d.error = std::current_exception();
  }
  room.with_lock([&] { return d.finished = true; });
  room.notify();
}

ProtocolChannel::Drive DdsProtocolChannel::drive(const std::function<bool(ProtocolMessage&&)>& step,
                                                 double timeout_s) {
  Driving d(step);
  session_.set_protocol_consumer([this, &d] { consume(d); });
  // Cleared before `d` goes: no listener thread is inside consume() after this returns.
  struct Clear {
    transport::Session& session;
    ~Clear() { session.set_protocol_consumer(nullptr); }
  } clear{session_};
  session_.consume_protocol();  // what came before
  transport::Mailroom& room = session_.mailroom();
  const std::uint32_t current = session_.epoch();
  using Clock = std::chrono::steady_clock;
  const auto timeout =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
  // Digests fall due while nothing arrives (a slow peer): wake once a period to let
  // consume() publish them.
  const auto slice =
      progress_
          ? std::min(timeout, std::chrono::duration_cast<Clock::duration>(progress_->period()))
          : timeout;
  auto last_progress = Clock::now();
  std::uint64_t seen = 0;
  for (;;) {
    const auto until = std::min(last_progress + timeout, Clock::now() + slice);
    const transport::WaitStatus st = room.wait_for(
        [&] { return d.finished || session_.writes_backlogged() || interrupted_locked(current); },
        std::chrono::duration<double>(until - Clock::now()));
    if (st == transport::WaitStatus::kStopped) throw RunStopped(room.stop_info()->reason);
    // Writes the listener threads could not make without waiting: this thread makes them.
    session_.flush_writes();
    if (room.with_lock([&] { return d.finished; })) {
      session_.set_protocol_consumer(nullptr);
      if (d.error) std::rethrow_exception(d.error);
      session_.flush_writes();  // the last step's, if deferred after the flush above
      return Drive::kDone;
    }
    if (st == transport::WaitStatus::kReady) {
      if (auto a = take_reassignment(session_)) throw RepartitionRequested(std::move(*a));
      if (auto r = take_rollback(session_)) throw *r;
      continue;  // only stale ones
    }
    const std::uint64_t handled = d.handled.load();
    if (handled != seen) {
      seen = handled;
      last_progress = Clock::now();
    } else if (Clock::now() >= last_progress + timeout) {
      return Drive::kTimeout;
    }
    session_.consume_protocol();  // a digest may be due
  }
}

std::optional<ProtocolMessage> DdsProtocolChannel::receive(double timeout_s) {
  return receive_after(timeout_s, 1);
}

std::optional<ProtocolMessage> DdsProtocolChannel::receive_after(double timeout_s,
                                                                 std::size_t wake_after) {
  // Back to a wake-up per message however this wait ends: the threshold is this step's only.
  struct ThresholdGuard {
    transport::Session& session;
    bool set;
    ~ThresholdGuard() {
      if (set) session.set_protocol_wake_threshold(1);
    }
  } guard{session_, wake_after > 1};
  if (guard.set) session_.set_protocol_wake_threshold(wake_after);
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::duration<double>(timeout_s));
  for (;;) {
    const std::uint32_t current = session_.epoch();
    auto& protocol = session_.protocol();
    // A digest falls due while we wait (a slow peer): wake for it, then wait on.
    const auto until = progress_ ? std::min(deadline, progress_->next_due()) : deadline;
    const double left =
        std::chrono::duration<double>(until - std::chrono::steady_clock::now()).count();
    const transport::WaitStatus st = session_.mailroom().wait_for(
        [&] { return interrupted_locked(current) || !protocol.queued_locked().empty(); },
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
    if (protocol.take(transport::Seconds(0), &out) != transport::WaitStatus::kReady)
      return std::nullopt;  // only stale rollbacks were queued; the caller waits again
    if (intercept_ && intercept_(out)) continue;  // e.g. a replica, not for the protocol
    note_status(out, false);
    return out;
  }
}

}  // namespace tessera::agent
