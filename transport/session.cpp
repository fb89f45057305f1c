// Session (session.hpp): opens the participant and the role's endpoints, then forwards each
// public call to the part that owns the concept (session_parts.hpp).

#include "transport/session.hpp"

#include <algorithm>
#include <chrono>
#include <variant>

#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"
#include "transport/security.hpp"
#include "transport/session_parts.hpp"
#include "transport/topic_names.hpp"

namespace tessera::transport {

SessionParts::SessionParts(const SessionOptions& options, int domain_id)
    : opt(options),
      net(network_profile(options.network)),
      domain(domain_id),
      me{options.run_id, options.coordinator, options.coordinator ? 0u : options.agent_id},
      trace(participant_name(me)),
      peers(room, opt, me),
      readiness(room, opt, me, peers, trace),
      router(room, protocol_in, me.agent_id),
      entities(opt, net, room, peers, readiness, trace),
      writer(entities, opt, me.coordinator, trace) {}

namespace {
int resolved_domain(const SessionOptions& options) {
  options.validate();
  return options.domain >= 0 ? options.domain : domain_for_run(options.run_id);
}
}  // namespace

Session::Session(const SessionOptions& options)
    : impl_(std::make_unique<SessionParts>(options, resolved_domain(options))) {
  SessionParts& s = *impl_;
  std::vector<std::pair<std::string, std::string>> security;
  if (!options.security_dir.empty())
    security = security_properties(security_files(
        options.security_dir, security_identity(options.coordinator, options.agent_id)));
  try {
    s.trace("creating the participant on domain %d", s.domain);
    s.entities.open(s.domain, s.me, security);
    s.trace("participant created");
    create_role_endpoints(s);
    s.trace("endpoints created");
  } catch (...) {
    s.entities.close(kExitRunFailed, participant_name(s.me));
    throw;
  }
}

Session::~Session() {
  close();
}

const SessionOptions& Session::options() const {
  return impl_->opt;
}
int Session::domain() const {
  return impl_->domain;
}
PeerIdentity Session::self() const {
  return impl_->me;
}
Mailroom& Session::mailroom() {
  return impl_->room;
}

Inbox<wire::AgentAnnouncement>& Session::announcements() {
  return impl_->announce_in;
}
Inbox<wire::PartitionAssignment>& Session::assignments() {
  return impl_->assignment_in;
}
Inbox<wire::MeasurementHandoff>& Session::handoffs() {
  return impl_->handoff_in;
}
Inbox<wire::MeasurementHandoff>& Session::replicas() {
  return impl_->replica_in;
}
Inbox<ProtocolMessage>& Session::protocol() {
  return impl_->protocol_in;
}
Inbox<wire::RoundStatus>& Session::status_watch() {
  return impl_->status_in;
}
Inbox<wire::FinalEstimate>& Session::finals() {
  return impl_->final_in;
}
Inbox<wire::Control>& Session::rejoins() {
  return impl_->rejoin_in;
}
Inbox<wire::Control>& Session::rollbacks() {
  return impl_->rollback_in;
}

std::uint32_t Session::epoch() const {
  return impl_->router.epoch();
}

void Session::set_epoch(std::uint32_t e) {
  impl_->router.set_epoch(e, protocol_id());
}

std::uint32_t Session::protocol_id() const {
  return impl_->router.protocol_id();
}

void Session::set_epoch(std::uint32_t e, std::uint32_t protocol_id) {
  impl_->renumbered = true;
  impl_->router.set_epoch(e, protocol_id);
}

void Session::publish(const wire::AgentAnnouncement& m) {
  impl_->writer.write(kAnnounceTopic, m);
}
void Session::publish(const wire::PartitionAssignment& m) {
  impl_->writer.write(kAssignmentTopic, m);
}
void Session::publish(const wire::MeasurementHandoff& m) {
  impl_->writer.write(kHandoffTopic, m);
}
void Session::publish(const wire::FinalEstimate& m) {
  impl_->writer.write(kFinalTopic, m);
}

void Session::send(const OutgoingMessage& m) {
  const std::string& run = impl_->opt.run_id;
  const std::uint32_t e = epoch();
  if (const auto* block = std::get_if<PoseBlockMessage>(&m.message)) {
    wire::PoseBlock w = to_wire_block(*block, run, m.broadcast, m.recipients);
    w.epoch(e);
    // Addressed blocks reach only their recipients (one sample on each one's own topic);
    // broadcasts, and everything after a renumbering re-partition, use the shared topic.
    if (m.broadcast || impl_->renumbered || impl_->opt.num_agents > kMaxAgentsWithRecipientTopics) {
      impl_->writer.write(kBlockTopic, w);
    } else {
      for (std::uint32_t k : m.recipients)
        if (k != impl_->me.agent_id) impl_->writer.write(block_topic_for(k), w);
    }
  } else {
    const auto& status = std::get<RoundStatusMessage>(m.message);
    wire::RoundStatus w = to_wire_status(status, run, m.broadcast, m.recipients);
    w.epoch(e);
    impl_->writer.write(coordinator_reads_status(status.phase) ? kStatusTopic : kAgentStatusTopic,
                        w);
  }
}

void Session::send_control(wire::ControlKind kind, const std::string& reason) {
  wire::Control c;
  c.run_id(impl_->opt.run_id);
  c.sender(impl_->me.coordinator ? kCoordinatorId : impl_->me.agent_id);
  c.kind(kind);
  c.reason(reason);
  impl_->writer.write(kControlTopic, c);
}

void Session::send_control(wire::Control c) {
  c.run_id(impl_->opt.run_id);
  c.sender(impl_->me.coordinator ? kCoordinatorId : impl_->me.agent_id);
  impl_->writer.write(kControlTopic, c);
}

void Session::send_abort(const std::string& cause, std::optional<std::uint32_t> origin) {
  wire::Control c;
  c.kind(wire::CONTROL_ABORT);
  c.reason(cause);
  c.agent(origin.value_or(impl_->me.coordinator ? kCoordinatorId : impl_->me.agent_id));
  send_control(std::move(c));
}

bool Session::endpoints_matched(std::string* missing) const {
  return impl_->readiness.endpoints_matched(missing);
}

WaitStatus Session::ready_barrier(Seconds timeout, std::string* missing) {
  return impl_->readiness.barrier(
      timeout, missing, [this] { send_control(wire::CONTROL_READY); },
      [this] { impl_->entities.trace_match_state("barrier timeout"); });
}

bool Session::finished() const {
  return impl_->readiness.finished();
}

WaitStatus Session::wait_finished(Seconds timeout) {
  return impl_->readiness.wait_finished(timeout);
}

std::vector<PeerIdentity> Session::live_peers() const {
  return impl_->peers.live_peers();
}

std::size_t Session::peers_ever_seen() const {
  return impl_->peers.peers_ever_seen();
}

void Session::set_peer_loss_fatal(bool fatal) {
  impl_->peers.set_loss_fatal(fatal);
}

void Session::set_agent_loss_tolerated(bool tolerated) {
  impl_->peers.set_agent_loss_tolerated(tolerated);
}

std::vector<std::uint32_t> Session::lost_agents() const {
  return impl_->peers.lost_agents();
}

void Session::flush(Seconds timeout) {
  impl_->writer.flush(timeout);
}

void Session::linger_for_control(Seconds timeout, Seconds unseen_patience) {
  const auto start = std::chrono::steady_clock::now();
  auto left = [&] {
    const Seconds rest = timeout - (std::chrono::steady_clock::now() - start);
    return rest > Seconds(0) ? rest : Seconds(0);
  };
  impl_->readiness.wait_coordinator_acknowledged(timeout);
  impl_->readiness.wait_matched_or_gone(std::string(kControlTopic) + "/w", left(),
                                        std::min(unseen_patience, left()));
  impl_->writer.wait_acknowledged(kControlTopic, left());
}

SessionStats Session::stats() const {
  return SessionStats{impl_->writer.bytes_sent(), impl_->writer.messages_sent(),
                      impl_->writer.write_retries(), impl_->protocol_samples.load()};
}

void Session::close() {
  close(kExitRunFailed);
}

void Session::close(int exit_code) {
  if (impl_) impl_->entities.close(exit_code, participant_name(impl_->me));
}

}  // namespace tessera::transport
