// Session (session.hpp): opens the participant and the role's endpoints, then forwards each
// shared call to the part that owns the concept (session_parts.hpp). The role's own calls are
// in agent_session.cpp and coordinator_session.cpp.

#include "transport/session.hpp"

#include <algorithm>
#include <chrono>

#include "transport/fastdds/successor_prefix.hpp"
#include "transport/run_failure.hpp"
#include "transport/security.hpp"
#include "transport/session_parts.hpp"
#include "transport/topic_names.hpp"
#include "transport/transport_error.hpp"

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
int resolved_domain(const SessionOptions& options, bool coordinator_role) {
  if (options.coordinator != coordinator_role)
    throw TransportError(std::string("a session of the ") +
                         (coordinator_role ? "coordinator" : "agent") +
                         " role was opened with the options of the other role");
  options.validate();
  return options.domain >= 0 ? options.domain : domain_for_run(options.run_id);
}

}  // namespace

Session::Session(const SessionOptions& options, bool coordinator_role)
    : impl_(std::make_unique<SessionParts>(options, resolved_domain(options, coordinator_role))) {
  SessionParts& s = *impl_;
  if (!options.security_dir.empty())
    s.security = security_properties(security_files(
        options.security_dir, security_identity(options.coordinator, options.agent_id)));
  ParticipantTags tags;
  tags.udp_only = !options.uses_shared_memory();
  try {
    s.trace("creating the participant on domain %d", s.domain);
    s.entities.open(s.domain, s.me, s.security, tags.encode());
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
      [this] { impl_->entities.trace_match_state("barrier timeout"); },
      std::string(kControlTopic) + "/r");
}

std::vector<PeerIdentity> Session::live_peers() const {
  return impl_->peers.live_peers();
}

std::vector<PeerView> Session::peer_views() const {
  const SessionParts& s = *impl_;
  const bool secured = !s.opt.security_dir.empty();
  std::vector<PeerView> views = s.peers.peer_views(secured);
  if (!secured) return views;
  // A handshake can finish on one side only (its last message lost): count a peer as
  // authenticated when both directions work, i.e. this process's control writer and reader
  // have matched the peer's (secure endpoint discovery needs both sides authenticated).
  const std::string w = std::string(kControlTopic) + "/w", r = std::string(kControlTopic) + "/r";
  std::lock_guard<std::mutex> lock(impl_->room.mutex());
  for (PeerView& v : views)
    v.authenticated = v.authenticated && s.readiness.has_matched_locked(w, v.who) &&
                      s.readiness.has_matched_locked(r, v.who);
  return views;
}

void Session::replace_participant(bool shared_memory, Seconds notice, const std::string& why) {
  SessionParts& s = *impl_;
  s.trace("replacing the participant: %s", why.c_str());
  const std::string name = participant_name(s.me);
  // 1. Tell the peers the old participant retires, so its leaving is no loss; give the news
  //    `notice` (a few announcement periods) to arrive. Peers that miss it still forget it
  //    when the new one appears (ParticipantTags::replaces).
  ParticipantTags tags;
  tags.udp_only = !s.opt.uses_shared_memory();
  tags.replaces = s.former_prefixes;
  tags.retiring = true;
  s.entities.set_user_data(tags.encode());
  s.room.wait_for([] { return false; }, notice, /*interruptible=*/false);
  // 2. Delete it before the new one exists (see ParticipantTags::retiring for why they never
  //    coexist), and forget what it had matched and authenticated.
  const GuidPrefix old = s.entities.retire();
  s.entities.close_retired(kExitRunFailed, name);
  s.readiness.forget_matches();
  s.peers.restart_handshakes();
  // 3. The new participant, naming every participant it replaces.
  s.opt.shared_memory = shared_memory;
  s.former_prefixes.push_back(prefix_text(old));
  tags.udp_only = !s.opt.uses_shared_memory();
  tags.retiring = false;
  tags.replaces = s.former_prefixes;
  // Not the prefix Fast DDS would derive: peers would take it for the old one.
  const GuidPrefix next = successor_prefix(old, !s.security.empty(), s.former_prefixes.size());
  try {
    s.entities.open(s.domain, s.me, s.security, tags.encode(), &next);
    create_role_endpoints(s);
  } catch (...) {
    s.entities.close(kExitRunFailed, name);
    throw;
  }
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
