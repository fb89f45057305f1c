// AgentSession (agent_session.hpp): the agent's inboxes, its epoch routing and its sends
// of the round protocol, forwarded to the parts that own them (session_parts.hpp).

#include "transport/agent_session.hpp"

#include <algorithm>
#include <chrono>
#include <string>
#include <utility>
#include <variant>

#include "transport/addressed_filter.hpp"
#include "transport/message_mapping.hpp"
#include "transport/report_mapping.hpp"
#include "transport/riding_blocks.hpp"
#include "transport/session_parts.hpp"
#include "transport/topic_names.hpp"

namespace tessera::transport {

namespace {

// A pose block as AgentSession::send writes it, to `recipients` (or everyone when `broadcast`).
void write_block(SessionParts& s, std::uint32_t epoch, const PoseBlockMessage& block,
                 bool broadcast, const std::vector<std::uint32_t>& recipients) {
  wire::PoseBlock w = to_wire_block(block, s.opt.run_id, broadcast, recipients);
  w.epoch(epoch);
  // Addressed blocks reach only their recipients (one sample on each one's own topic);
  // broadcasts, and everything after a renumbering re-partition, use the shared topic.
  if (broadcast || s.renumbered) {
    s.writer.write(kBlockTopic, w);
  } else if (s.opt.num_agents > kMaxAgentsWithRecipientTopics) {
    // One sample; the filter picks the recipients, if it can (addressed_filter.hpp).
    s.writer.write(
        serialized_size(w) <= kMaxAddressedSampleBytes ? kAddressedBlockTopic : kBlockTopic, w);
  } else {
    for (std::uint32_t k : recipients)
      if (k != s.me.agent_id) s.writer.write(block_topic_for(k), w);
  }
}
}  // namespace

AgentSession::AgentSession(const SessionOptions& options) : Session(options, false) {}

Inbox<wire::PartitionAssignment>& AgentSession::assignments() {
  return parts().assignment_in;
}
Inbox<wire::MeasurementHandoff>& AgentSession::handoffs() {
  return parts().handoff_in;
}
Inbox<wire::MeasurementHandoff>& AgentSession::replicas() {
  return parts().replica_in;
}
Inbox<ProtocolMessage>& AgentSession::protocol() {
  return parts().protocol_in;
}

void AgentSession::set_protocol_wake_threshold(std::size_t n) {
  parts().router.set_wake_threshold(n);
}
void AgentSession::set_protocol_awaited(std::optional<AwaitedMessages> awaited) {
  parts().router.set_awaited(std::move(awaited));
}
bool AgentSession::protocol_ready_locked() const {
  return parts().router.ready_locked();
}
Inbox<wire::Control>& AgentSession::rollbacks() {
  return parts().rollback_in;
}

std::uint32_t AgentSession::epoch() const {
  return parts().router.epoch();
}

void AgentSession::set_epoch(std::uint32_t e) {
  parts().router.set_epoch(e, protocol_id());
}

std::uint32_t AgentSession::protocol_id() const {
  return parts().router.protocol_id();
}

void AgentSession::set_epoch(std::uint32_t e, std::uint32_t protocol_id) {
  parts().renumbered = true;
  parts().router.set_epoch(e, protocol_id);
}

void AgentSession::publish(const wire::AgentAnnouncement& m) {
  parts().writer.write(kAnnounceTopic, m);
}
void AgentSession::publish(const wire::MeasurementHandoff& m, double write_timeout_s) {
  parts().writer.write(m.purpose() == 0 ? kAddressedHandoffTopic : kHandoffTopic, m,
                       write_timeout_s);
}
void AgentSession::publish(const wire::FinalEstimate& m) {
  parts().writer.write(kFinalTopic, m);
}
void AgentSession::publish(wire::AgentProgress m) {
  m.run_id(parts().opt.run_id);
  parts().writer.write(kProgressTopic, m);
}

void AgentSession::report(const agent::AgentReport& r) {
  parts().writer.write(kReportTopic,
                       to_wire_report(r, parts().opt.run_id, parts().me.agent_id, epoch()));
}

void AgentSession::send(const OutgoingMessage& m) {
  const std::string& run = parts().opt.run_id;
  const std::uint32_t e = epoch();
  if (const auto* block = std::get_if<PoseBlockMessage>(&m.message)) {
    write_block(parts(), e, *block, m.broadcast, m.recipients);
  } else {
    const auto& status = std::get<RoundStatusMessage>(m.message);
    wire::RoundStatus w = to_wire_status(status, run, m.broadcast, m.recipients);
    w.epoch(e);
    if (relayed_phase(status.phase) && parts().relays_statuses()) {
      if (parts().me.agent_id != kRelayAgent) {
        parts().writer.write(kRelayStatusTopic, w);
        return;
      }
      // The relay's own status completes a step when the others' came first.
      parts().room.with_lock([&] { return parts().relay.add(w, parts().router.epoch_locked()); });
      relay_statuses();
      return;
    }
    parts().writer.write(coordinator_reads_status(status.phase, parts().rounds_followed)
                             ? kStatusTopic
                             : kAgentStatusTopic,
                         w);
  }
}

void AgentSession::send_all(const std::vector<OutgoingMessage>& messages) {
  SessionParts& s = parts();
  const std::uint32_t me = s.me.agent_id;
  const bool to_relay = s.relays_statuses() && me != kRelayAgent && !s.renumbered &&
                        s.opt.num_agents <= kMaxAgentsWithRecipientTopics;
  // This step's status for the relay (a step has at most one; the first counts).
  const OutgoingMessage* status = nullptr;
  if (to_relay)
    for (const auto& m : messages)
      if (const auto* st = std::get_if<RoundStatusMessage>(&m.message);
          st && relayed_phase(st->phase)) {
        status = &m;
        break;
      }
  const auto rides = [&](const OutgoingMessage& m) {
    const auto* b = std::get_if<PoseBlockMessage>(&m.message);
    return status && b && !m.broadcast && rides_with_status(b->phase) &&
           std::find(m.recipients.begin(), m.recipients.end(), kRelayAgent) != m.recipients.end();
  };
  if (!status || std::none_of(messages.begin(), messages.end(), rides)) {
    for (const auto& m : messages) send(m);
    return;
  }
  for (const auto& m : messages) {
    if (&m == status) {
      wire::RoundStatus w = to_wire_status(std::get<RoundStatusMessage>(m.message), s.opt.run_id,
                                           m.broadcast, m.recipients);
      w.epoch(epoch());
      for (const auto& b : messages)
        if (rides(b)) attach_block(w, std::get<PoseBlockMessage>(b.message));
      s.writer.write(kRelayStatusTopic, w);
    } else if (rides(m)) {
      std::vector<std::uint32_t> others;  // its other recipients get it as usual
      for (std::uint32_t k : m.recipients)
        if (k != kRelayAgent) others.push_back(k);
      if (!others.empty())
        write_block(s, epoch(), std::get<PoseBlockMessage>(m.message), false, others);
    } else {
      send(m);
    }
  }
}

void AgentSession::set_round_traffic(const RoundTraffic& traffic) {
  parts().relay_enabled = traffic.status_relay;
  parts().rounds_followed = traffic.coordinator_follows_rounds;
}

void AgentSession::relay_statuses() {
  SessionParts& s = parts();
  if (!s.relays_statuses() || s.me.agent_id != kRelayAgent) return;
  std::vector<wire::RoundStatus> bundles =
      s.room.with_lock([&] { return s.relay.take_bundles(s.opt.run_id, kRelayAgent); });
  // Bundles carry solve statuses: the coordinator's topic only when it follows them.
  const char* topic = s.rounds_followed ? kStatusTopic : kAgentStatusTopic;
  for (const auto& b : bundles) s.writer.write(topic, b);
}

bool AgentSession::finished() const {
  return parts().readiness.finished();
}

const std::atomic<bool>& AgentSession::finished_flag() const {
  return parts().readiness.finished_flag();
}

WaitStatus AgentSession::wait_finished(Seconds timeout) {
  return parts().readiness.wait_finished(timeout);
}

bool AgentSession::handoffs_acknowledged(Seconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  return parts().writer.wait_acknowledged(kAddressedHandoffTopic, timeout) &&
         parts().writer.wait_acknowledged(
             kHandoffTopic,
             std::max(Seconds(0), Seconds(until - std::chrono::steady_clock::now())));
}

}  // namespace tessera::transport
