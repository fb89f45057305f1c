#pragma once
// One DDS participant per process and everything it needs for a Tessera run: the topics
// with their QoS, typed writers that retry while the bounded history is full, inboxes fed
// by listener threads, a readiness barrier, and peer-loss detection. DDS types stay inside
// the implementation; callers see the generated wire structs (idl/) and core's
// ProtocolMessage only.
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
#include <tessera/protocol/awaited_messages.hpp>
#include <tessera/protocol/messages.hpp>
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

class Session {
 public:
  /// Creates the participant and this role's endpoints; throws TransportError on failure.
  explicit Session(const SessionOptions& options);
  /// Same as close().
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  const SessionOptions& options() const;
  int domain() const;
  PeerIdentity self() const;
  /// Stop state shared by every inbox; request_stop() interrupts all waits.
  Mailroom& mailroom();

  // ---- inboxes: messages of this run meant for this process ------------------------------
  Inbox<wire::AgentAnnouncement>& announcements();  ///< Coordinator.
  Inbox<wire::PartitionAssignment>& assignments();  ///< Agents.
  Inbox<wire::MeasurementHandoff>& handoffs();
  /// Agents: replicas of other agents' local problems (hand-offs with purpose 1) addressed to
  /// this agent; kept apart so they never count as hand-offs.
  Inbox<wire::MeasurementHandoff>& replicas();  ///< Agents: those addressed to this agent.
  /// Agents: pose blocks and round statuses addressed to this agent (own messages excluded),
  /// converted to core's types, in arrival order per topic.
  Inbox<ProtocolMessage>& protocol();
  /// Agents: the listeners wake the mailroom's waiters for a protocol message only once
  /// `n` (>= 1; 1 is the default: every message) are queued in protocol(). For a receiver that
  /// knows how many messages its current step needs; every other wake-up (stop, rollback,
  /// re-partition, new epoch) is unchanged. Set it back to 1 after the wait.
  void set_protocol_wake_threshold(std::size_t n);
  /// Agents: instead of a count, the listeners wake the waiters for a protocol message only
  /// once a message of every awaited sender is queued (nullopt: back to the count). For a
  /// receiver whose step names what it lacks (AgentProcess::awaited); a count would also
  /// count messages of later steps. Other wake-ups are unchanged. Reset it after the wait.
  void set_protocol_awaited(std::optional<AwaitedMessages> awaited);
  /// Whether protocol() holds what the current wait needs: every awaited message when
  /// set_protocol_awaited named some, else any message. Requires the mailroom lock.
  bool protocol_ready_locked() const;
  /// Coordinator: the round statuses it reads (topic_names.hpp, coordinator_reads_status).
  Inbox<wire::RoundStatus>& status_watch();
  /// Coordinator: the agents' progress digests (agent/progress_digest.hpp).
  Inbox<wire::AgentProgress>& progress();
  Inbox<wire::FinalEstimate>& finals();  ///< Coordinator.
  Inbox<wire::Control>& rejoins();       ///< Coordinator: REJOIN requests of restarted agents.
  Inbox<wire::Control>& rollbacks();     ///< Agents: ROLLBACK orders of the coordinator.

  // ---- rollback epochs: protocol messages carry the sender's epoch; those of an older
  // epoch are dropped, those of a newer one are held until this process reaches it.
  std::uint32_t epoch() const;
  /// Moves to `epoch` (>= the current one): drops queued protocol messages of older epochs
  /// and releases the held ones of this epoch into protocol().
  void set_epoch(std::uint32_t epoch);
  /// Same, and from then on this agent is `protocol_id` in the round protocol (a re-partition
  /// for survivors renumbers them 0..S-1): incoming messages are routed by it. Held messages
  /// of `epoch` are routed by it when released.
  void set_epoch(std::uint32_t epoch, std::uint32_t protocol_id);
  /// This agent's id in the round protocol of the current epoch (its agent id at first).
  std::uint32_t protocol_id() const;

  // ---- sending (retries while the history is full; throws TransportError after write_timeout_s)
  void publish(const wire::AgentAnnouncement& m);
  void publish(const wire::PartitionAssignment& m);
  void publish(const wire::MeasurementHandoff& m);
  void publish(const wire::FinalEstimate& m);
  /// Agents: a progress digest for the coordinator (run id filled in here).
  void publish(wire::AgentProgress m);
  /// A round-protocol message from this agent (run id and routing filled in here). Round
  /// statuses of the solve go through the relay agent in runs of at least 3 agents
  /// (transport/status_relay.hpp): to it alone, and from it to everyone as one bundle per step.
  void send(const OutgoingMessage& m);
  /// The messages of one protocol step, as send() each, except that on an agent whose status
  /// goes to the relay, pose blocks of the solve addressed to the relay ride in that status's
  /// sample (wire RoundStatus::blocks) instead of one sample each: one delivery (one wake-up
  /// of the relay's receive thread) less per block. The relay routes them as if they had come
  /// on its block topic; core buffers solve messages by (round, phase, sender), so their
  /// order relative to other blocks does not matter.
  void send_all(const std::vector<OutgoingMessage>& messages);
  /// On the relay agent: sends the status bundles of the steps completed since the last call
  /// (their last status came in on a listener thread, which must not write). Call whenever a
  /// wait for protocol messages ends; nothing to do on any other process.
  void relay_statuses();
  /// Round statuses through the relay (see send()) or, off (the default), all to all. Every
  /// agent of a run must choose the same before its first round status. Off where the
  /// coordinator arbitrates lost agents: it then reads each agent's round from its own status.
  void set_status_relay(bool on);
  /// Whether core's round statuses of the solve (and the relay's bundles) also go to the
  /// coordinator (topic_names.hpp, coordinator_reads_status): on while it arbitrates lost
  /// agents (rejoin, replicas); off (the default) it follows the agents' progress digests.
  /// Every agent of a run must choose the same before its first round status.
  void set_coordinator_follows_rounds(bool on);
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
  /// Whether the coordinator has published FINISHED (agents).
  bool finished() const;
  /// The same, readable without a lock (from a signal handler); valid while the session lives.
  const std::atomic<bool>& finished_flag() const;
  /// Waits for FINISHED from the coordinator.
  WaitStatus wait_finished(Seconds timeout);

  /// Peers of this run discovered and not lost.
  std::vector<PeerIdentity> live_peers() const;
  /// Live peers with what is known of them before any message (age, DDS Security handshake
  /// done, participant tags).
  std::vector<PeerView> peer_views() const;
  /// Re-creates this process's participant (new GUID, same role and identity; UDP only when
  /// `shared_memory` is false) and its endpoints. The old participant first announces that it
  /// retires and is deleted `notice` later; the new one names every participant it replaces.
  /// Peers forget the old one silently (ParticipantTags) instead of treating it as lost or as
  /// a second process of the same role. Only before this process has written anything (e.g. a
  /// stalled DDS Security handshake before an agent announces itself, transport/peer_gate.hpp):
  /// samples and matches of the old participant are dropped. Throws TransportError.
  void replace_participant(bool shared_memory, Seconds notice, const std::string& why);
  /// Number of peers of this run ever discovered (lost ones included).
  std::size_t peers_ever_seen() const;
  /// When false, a lost peer is only logged (set it once the run's work is complete).
  void set_peer_loss_fatal(bool fatal);
  /// See SessionOptions::tolerate_agent_loss.
  void set_agent_loss_tolerated(bool tolerated);
  /// Agents that were discovered and lost, with no live process of the same id since.
  std::vector<std::uint32_t> lost_agents() const;
  /// Waits until every reliable sample written so far is acknowledged (bounded).
  void flush(Seconds timeout);
  /// Waits at most `timeout` until every hand-off this process published is acknowledged by
  /// every matched reader, i.e. held in the recipients' queues even if this process dies
  /// now (volatile samples are not repaired once their writer is gone). True if so.
  bool handoffs_acknowledged(Seconds timeout);
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

 private:
  std::unique_ptr<SessionParts> impl_;  // session_parts.hpp
};

}  // namespace tessera::transport
