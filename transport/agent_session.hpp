#pragma once
// An agent's DDS session: the shared part (transport/session.hpp) plus what only agents read
// and send: the coordinator's assignments and rollback orders, the other agents' hand-offs
// and replicas, the round protocol (pose blocks and round statuses, routed by rollback epoch,
// sent all to all or through the status relay) and the coordinator's FINISHED.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <tessera/protocol/awaited_messages.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

#include "runtime/agent_report.hpp"
#include "tessera.h"
#include "transport/inbox.hpp"
#include "transport/round_traffic.hpp"
#include "transport/session.hpp"
#include "transport/session_options.hpp"

namespace tessera::transport {

class AgentSession final : public Session {
 public:
  /// Creates the participant and the agent endpoints of agent `options.agent_id`
  /// (`options.coordinator` must be false); throws InputError for bad options, TransportError
  /// on failure.
  explicit AgentSession(const SessionOptions& options);

  // ---- inboxes: messages of this run meant for this agent ---------------------------------
  Inbox<wire::PartitionAssignment>& assignments();
  Inbox<wire::MeasurementHandoff>& handoffs();  ///< Those addressed to this agent.
  /// Replicas of other agents' local problems (hand-offs with purpose 1) addressed to this
  /// agent; kept apart so they never count as hand-offs.
  Inbox<wire::MeasurementHandoff>& replicas();
  /// Pose blocks and round statuses addressed to this agent (own messages excluded),
  /// converted to core's types, in arrival order per topic.
  Inbox<ProtocolMessage>& protocol();
  Inbox<wire::Control>& rollbacks();  ///< ROLLBACK orders of the coordinator.

  // ---- waking for protocol messages ------------------------------------------------------
  /// The listeners wake the mailroom's waiters for a protocol message only once `n` (>= 1; 1
  /// is the default: every message) are queued in protocol(). For a receiver that knows how
  /// many messages its current step needs; every other wake-up (stop, rollback,
  /// re-partition, new epoch) is unchanged. Set it back to 1 after the wait.
  void set_protocol_wake_threshold(std::size_t n);
  /// Instead of a count, the listeners wake the waiters for a protocol message only once a
  /// message of every awaited sender is queued (nullopt: back to the count). For a receiver
  /// whose step names what it lacks (AgentProcess::awaited); a count would also count
  /// messages of later steps. Other wake-ups are unchanged. Reset it after the wait.
  void set_protocol_awaited(std::optional<AwaitedMessages> awaited);
  /// Whether protocol() holds what the current wait needs: every awaited message when
  /// set_protocol_awaited named some, else any message. Requires the mailroom lock.
  bool protocol_ready_locked() const;

  // ---- rollback epochs: protocol messages carry the sender's epoch; those of an older
  // epoch are dropped, those of a newer one are held until this agent reaches it.
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
  /// `write_timeout_s` > 0: how long the write may wait for acknowledgements (see
  /// SampleWriter::write); 0 = the session's write timeout.
  void publish(const wire::MeasurementHandoff& m, double write_timeout_s = 0);
  void publish(const wire::FinalEstimate& m);
  /// A progress digest for the coordinator (run id filled in here).
  void publish(wire::AgentProgress m);
  /// One of agent 0's reports, to the coordinator alone (kReportTopic; run id, this agent's id
  /// and the current epoch filled in here).
  void report(const agent::AgentReport& r);
  /// How round statuses travel (round_traffic.hpp). Every agent of a run must choose the same
  /// before its first round status; until then the defaults hold.
  void set_round_traffic(const RoundTraffic& traffic);
  /// A round-protocol message from this agent (run id and routing filled in here). With the
  /// status relay, round statuses of the solve go to the relay agent alone, and from it to
  /// everyone as one bundle per step (transport/status_relay.hpp).
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
  /// wait for protocol messages ends; nothing to do on any other agent.
  void relay_statuses();
  /// Waits at most `timeout` until every hand-off this agent published is acknowledged by
  /// every matched reader, i.e. held in the recipients' queues even if this process dies
  /// now (volatile samples are not repaired once their writer is gone). True if so.
  bool handoffs_acknowledged(Seconds timeout);

  // ---- the end of the run ------------------------------------------------------------------
  /// Whether the coordinator has published FINISHED.
  bool finished() const;
  /// The same, readable without a lock (from a signal handler); valid while the session lives.
  const std::atomic<bool>& finished_flag() const;
  /// Waits for FINISHED from the coordinator.
  WaitStatus wait_finished(Seconds timeout);
};

}  // namespace tessera::transport
