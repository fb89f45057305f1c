#pragma once
// Which participants of this run a process has discovered and lost, and what a loss does:
// a lost peer stops the session (Mailroom::request_stop) unless losses are not fatal (the
// run's work is done) or it is an agent and agent losses are tolerated. Also detects two
// processes claiming the same role. Internal to transport/; state is guarded by the
// mailroom's mutex (the *_locked members require it held).
//
// In a secured run (SessionOptions::security_dir set) a participant's name and USER_DATA
// arrive in plaintext SPDP before any handshake, so anyone on the network can advertise a
// run member's name. Such a participant is only a *candidate* until Fast DDS reports its
// DDS Security handshake authorized: until then it claims no role (no "two processes
// claim"), its tags decide nothing (replaces, retiring, udp_only), and its leaving is no
// loss. The peer gate still sees candidates (unauthenticated PeerViews) to detect a stalled
// handshake.

#include <chrono>
#include <fastdds/rtps/common/GuidPrefix_t.hpp>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "transport/dds_trace.hpp"
#include "transport/inbox.hpp"
#include "transport/participant_tags.hpp"
#include "transport/peer_view.hpp"
#include "transport/run_identity.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport {

/// A DDS participant's GUID prefix: how listeners name the remote side of an event.
using GuidPrefix = eprosima::fastrtps::rtps::GuidPrefix_t;

/// "01.0f.78.fd..." (Fast DDS's own text form; what ParticipantTags::replaces carries).
std::string prefix_text(const GuidPrefix& prefix);

class PeerTracker {
 public:
  PeerTracker(Mailroom& room, const SessionOptions& options, PeerIdentity me);

  /// This process's participant (set once it exists): events about it are ignored. A
  /// process that re-creates its participant (Session::replace_participant) adds each new
  /// one; events about its earlier ones stay ignored too (they briefly coexist). Set before
  /// the participant's listener can fire (it is set from the listener's own thread at the
  /// latest), read by listener threads afterwards.
  void add_own_prefix(const GuidPrefix& prefix);
  bool is_own(const GuidPrefix& prefix) const;

  /// A participant of this run appeared as `who` with `tags` (its USER_DATA). In a secured
  /// run it stays a candidate (see above) until authenticated() admits it; unsecured, or
  /// once admitted: when the tags say it replaces participant P of the same role, P is
  /// forgotten silently (no loss, no clash; a pending stop for P's clean leave is withdrawn).
  /// Otherwise stops the session with exit code 2 when another live process already claims
  /// the same role (or this process's own role).
  void discovered(const GuidPrefix& prefix, const PeerIdentity& who,
                  const ParticipantTags& tags = {});
  /// The participant `prefix` changed its QoS; with `tags.retiring` it is forgotten silently
  /// (its process is about to replace it: no loss, no stop when it leaves).
  void changed(const GuidPrefix& prefix, const ParticipantTags& tags);
  /// DDS Security: the handshake with `prefix` completed (authorized). The first time, a
  /// candidate of that prefix is admitted as discovered() describes (the report may also
  /// come before the discovery; then discovered() admits it at once).
  void authenticated(const GuidPrefix& prefix);
  /// This process's participant was replaced: handshakes start afresh (none counts as
  /// authenticated, every peer's age restarts now).
  void restart_handshakes();
  /// The peer left cleanly: the stop (if fatal) waits 2 s so an ABORT that says why can
  /// arrive first and name the cause.
  void left(const GuidPrefix& prefix);
  /// The peer's participant lease expired.
  void dropped(const GuidPrefix& prefix);
  /// One of the peer's writers lost its liveliness. Not proof that the peer died: a process
  /// SIGKILLed while writing into a shared-memory port leaves that port locked, and the
  /// receiver then stops hearing *every* peer through it, so the first writer whose
  /// liveliness lapses may belong to a live peer. The peer is therefore not marked lost; a
  /// fatal stop naming it only takes effect after kLivelinessStopDelayS, so the participant
  /// lease of the process that really died (announced over UDP, not through the locked port)
  /// names it first.
  void liveliness_lost(const GuidPrefix& prefix);
  static constexpr double kLivelinessStopDelayS = 0.5;

  /// When false, a lost peer is only logged.
  void set_loss_fatal(bool fatal);
  /// See SessionOptions::tolerate_agent_loss.
  void set_agent_loss_tolerated(bool tolerated);

  std::vector<PeerIdentity> live_peers() const;
  /// Every live peer with its age, authentication state (`secured` false: always true) and
  /// tags; in a secured run followed by every candidate (unauthenticated, possibly an
  /// impostor of a member's name).
  std::vector<PeerView> peer_views(bool secured) const;
  std::size_t peers_ever_seen() const;
  /// Agents discovered and lost, with no live process of the same id since.
  std::vector<std::uint32_t> lost_agents() const;

  // ---- with the mailroom's mutex held ------------------------------------------------------
  /// The peer of `prefix` if discovered (lost or not), else nullptr.
  const PeerIdentity* known_locked(const GuidPrefix& prefix) const;
  /// The peer of `prefix` if discovered and not lost, else nullptr.
  const PeerIdentity* live_locked(const GuidPrefix& prefix) const;
  /// Every peer ever discovered, by prefix.
  const std::map<GuidPrefix, PeerIdentity>& all_locked() const { return peers_; }
  bool lost_locked(const GuidPrefix& prefix) const { return lost_.count(prefix) > 0; }
  /// "agent 2", "agent 2 (lost)" or "unknown <prefix>" (for traces; the lock is not needed
  /// while tracing is off, as then nothing is printed).
  std::string describe_locked(const GuidPrefix& prefix) const;

 private:
  using Clock = std::chrono::steady_clock;
  /// The role claim and its consequences (see discovered()), for an admitted participant.
  void admit(const GuidPrefix& prefix, const PeerIdentity& who, const ParticipantTags& tags,
             Clock::time_point discovered_at);
  void gone(const GuidPrefix& prefix, const std::string& how, bool graceful);
  std::string left_reason(const PeerIdentity& who) const;

  Mailroom& room_;
  const SessionOptions& opt_;
  PeerIdentity me_;
  mutable std::mutex own_mutex_;
  std::set<GuidPrefix> own_prefixes_;
  std::map<GuidPrefix, PeerIdentity> peers_;  // participants of this run, by GUID prefix
  std::set<GuidPrefix> lost_;
  std::set<std::string> replaced_;      // prefix_text() of participants replaced by a new one
  std::set<GuidPrefix> authenticated_;  // handshake done with this process's current participant
  std::map<GuidPrefix, Clock::time_point> discovered_at_;
  // Secured runs only: participants seen in discovery but never authenticated, and those
  // authenticated at least once (by any of this process's participants).
  struct Candidate {
    PeerIdentity who;
    ParticipantTags tags;
    Clock::time_point discovered_at;
  };
  std::map<GuidPrefix, Candidate> candidates_;
  std::set<GuidPrefix> admitted_;
  std::map<GuidPrefix, ParticipantTags> tags_;
  bool loss_fatal_ = true;
  bool tolerate_agent_loss_ = false;
  const bool secured_;  // SessionOptions::security_dir set
};

}  // namespace tessera::transport
