#pragma once
// One DDS participant per process and what every process of a Tessera run needs from it,
// whatever its role: identity, the shared stop state (mailroom), control messages
// (READY/ABORT/REJOIN/ROLLBACK), the readiness barrier, peer tracking and loss policy,
// participant replacement, flush and teardown. A process opens the session of its role,
// which adds that role's inboxes and sends: AgentSession (transport/agent_session.hpp) or
// CoordinatorSession (transport/coordinator_session.hpp). DDS types stay inside the
// implementation; callers see the generated wire structs (idl/) and core's ProtocolMessage.
//
// Implementation, one concept a file (all internal to transport/): session_parts.hpp (what a
// session is made of), dds_entities (participant, topics, readers, writers, teardown),
// dds_listeners (Fast DDS callbacks -> the trackers), peer_tracking (discovered / lost
// peers, what a loss does), readiness (endpoint matches, READY/FINISHED, barrier),
// epoch_routing (protocol messages by rollback epoch), sample_writing (writes with retry,
// counters), role_endpoints.cpp (which topics each role uses, where samples go),
// dds_trace (TESSERA_DDS_TRACE).
//
// Isolation: domain id (derived from the run id unless given), Partition QoS = run id,
// and the run id field of every message (messages of other runs are dropped).
//
// Failure: a peer of this run that disappears (participant lease or writer liveliness
// expires, or it leaves) or that publishes ABORT stops the session: every wait returns
// WaitStatus::kStopped and mailroom().stop_info() names the cause.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tessera.h"
#include "transport/inbox.hpp"
#include "transport/peer_view.hpp"
#include "transport/run_identity.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport {

struct SessionParts;

/// Counters of one session (this process).
struct SessionStats {
  std::uint64_t bytes_sent = 0;  ///< Serialized payload bytes written (all topics).
  std::uint64_t messages_sent = 0;
  std::uint64_t write_retries = 0;  ///< Writes that found the history full and waited.
  /// Agents: round-protocol samples (pose blocks, round statuses) that reached this process,
  /// counted before routing, i.e. including any not addressed to it.
  std::uint64_t protocol_samples_received = 0;
};

/// The part of a session both roles share. Not created directly: open an AgentSession or a
/// CoordinatorSession; code that works for either role takes a Session&.
class Session {
 public:
  /// Same as close().
  virtual ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const SessionOptions& options() const;
  int domain() const;
  PeerIdentity self() const;
  /// Stop state shared by every inbox; request_stop() interrupts all waits.
  Mailroom& mailroom();

  // ---- control (every process reads every other's) ---------------------------------------
  /// READY / FINISHED from this process (ABORT: send_abort).
  void send_control(wire::ControlKind kind, const std::string& reason = "");
  /// ABORT: the run stops because of `cause`, a failure of process `origin` (agent id, or
  /// kCoordinatorId; nullopt: this process). A process relaying an ABORT it received passes
  /// the received StopInfo's origin and cause, so the receivers name the first cause.
  void send_abort(const std::string& cause, std::optional<std::uint32_t> origin = std::nullopt);
  /// A control message with its REJOIN / ROLLBACK fields set by the caller (run id and
  /// sender are filled in here).
  void send_control(wire::Control message);

  // ---- run coordination ----------------------------------------------------------------
  /// Whether every volatile endpoint of this process has matched every peer of a complete
  /// run (the other agents, the coordinator). When false, `missing` (if given) lists them.
  bool endpoints_matched(std::string* missing = nullptr) const;
  /// Waits until endpoints_matched(), publishes READY, then waits for READY from every
  /// other agent (and the coordinator, for agents). After kReady, volatile messages between
  /// any two processes of the run cannot be lost to discovery races. On kTimeout `missing`
  /// names who is not ready.
  WaitStatus ready_barrier(Seconds timeout, std::string* missing);

  // ---- peers ----------------------------------------------------------------------------
  /// Peers of this run discovered and not lost.
  std::vector<PeerIdentity> live_peers() const;
  /// Live peers with what is known of them before any message (age, DDS Security handshake
  /// done, participant tags).
  std::vector<PeerView> peer_views() const;
  /// Number of peers of this run ever discovered (lost ones included).
  std::size_t peers_ever_seen() const;
  /// Agents that were discovered and lost, with no live process of the same id since.
  std::vector<std::uint32_t> lost_agents() const;
  /// When false, a lost peer is only logged (set it once the run's work is complete).
  void set_peer_loss_fatal(bool fatal);
  /// See SessionOptions::tolerate_agent_loss.
  void set_agent_loss_tolerated(bool tolerated);
  /// Re-creates this process's participant (new GUID, same role and identity; UDP only when
  /// `shared_memory` is false) and its endpoints. The old participant first announces that it
  /// retires and is deleted `notice` later; the new one names every participant it replaces.
  /// Peers forget the old one silently (ParticipantTags) instead of treating it as lost or as
  /// a second process of the same role. Only before this process has written anything (e.g. a
  /// stalled DDS Security handshake before an agent announces itself, transport/peer_gate.hpp):
  /// samples and matches of the old participant are dropped. Throws TransportError.
  void replace_participant(bool shared_memory, Seconds notice, const std::string& why);

  // ---- leaving ----------------------------------------------------------------------------
  /// Waits until every reliable sample written so far is acknowledged (bounded).
  void flush(Seconds timeout);
  /// Before leaving on an error, all within `timeout`: an agent first waits until the
  /// coordinator acknowledged the abort (sent its own ABORT) or is gone, discovered or not
  /// (the coordinator must name the cause; matching our writer to its reader is not enough,
  /// since its reader may not have matched our writer yet); then every process waits until
  /// the control topic has matched every peer of the run and they acknowledged what this
  /// process wrote, so an ABORT written just before reaches processes still starting up.
  /// Peers never discovered are waited for only `unseen_patience` (they may not exist).
  void linger_for_control(Seconds timeout, Seconds unseen_patience = Seconds(1.0));

  SessionStats stats() const;
  /// Deletes every DDS entity and the participant (idempotent). After this the process
  /// leaves no shared-memory files behind. Same as close(1).
  void close();
  /// Same, for a process about to exit with `exit_code`: if Fast DDS aborts or hangs while
  /// the participant is deleted (known Fast DDS 2.9 teardown bugs,
  /// transport/fastdds/teardown_guard.hpp), the process exits at once with `exit_code` instead of
  /// crashing or hanging.
  void close(int exit_code);

 protected:
  /// Creates the participant and the endpoints of the role `options.coordinator` names, which
  /// must be `coordinator_role` (the subclass's); throws InputError for bad options,
  /// TransportError on failure.
  Session(const SessionOptions& options, bool coordinator_role);
  SessionParts& parts() { return *impl_; }
  const SessionParts& parts() const { return *impl_; }

 private:
  std::unique_ptr<SessionParts> impl_;  // session_parts.hpp
};

}  // namespace tessera::transport
