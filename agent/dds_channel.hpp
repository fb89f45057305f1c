#pragma once
// The ProtocolChannel of the DDS runtime: core ProtocolMessages over an agent's AgentSession.
// A ROLLBACK order of the coordinator (newer epoch than this process's) interrupts a wait
// with RollbackRequested.

#include <functional>
#include <optional>
#include <stdexcept>

#include "agent/progress_digest.hpp"
#include "runtime/round_loop.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

class DdsProtocolChannel : public ProtocolChannel {
 public:
  explicit DdsProtocolChannel(transport::AgentSession& session) : session_(session) {}
  void send(const OutgoingMessage& message) override;
  /// AgentSession::send_all: blocks to the status relay ride in the step's status sample.
  void send_all(const std::vector<OutgoingMessage>& messages) override;
  /// On the coordinator's report topic (AgentSession::report).
  void report(const AgentReport& report) override;
  std::optional<ProtocolMessage> receive(double timeout_s) override;
  /// The listener wakes this thread only once `wake_after` protocol messages are queued
  /// (AgentSession::set_protocol_wake_threshold); rollbacks, re-partitions and stops as receive().
  std::optional<ProtocolMessage> receive_after(double timeout_s, std::size_t wake_after) override;
  /// The listener wakes this thread only once every awaited message is queued
  /// (AgentSession::set_protocol_awaited); rollbacks, re-partitions and stops as receive(). With an
  /// intercept set (replicas): receive_after(timeout_s, awaited.senders.size()) instead.
  std::optional<ProtocolMessage> receive_awaiting(double timeout_s,
                                                  const AwaitedMessages& awaited) override;
  /// Messages for which `f` returns true are consumed by it instead of being returned
  /// (lifted-pose replicas of other agents).
  void set_intercept(std::function<bool(const ProtocolMessage&)> f) { intercept_ = std::move(f); }

  /// From now on, publishes this agent's progress digests (agent/progress_digest.hpp) from
  /// its sends and waits: every `options.period_s` while it runs rounds (waits end early to
  /// send them), at once on agent 0 when the first and each restart step complete. For runs
  /// whose coordinator does not read the round statuses themselves.
  void report_progress(std::uint32_t agent, std::uint32_t num_agents,
                       ProgressDigestOptions options = {});
  /// The solve is over: the last digest (nothing when report_progress was not called).
  void publish_final_progress();

 private:
  void note_status(const ProtocolMessage& m, bool own);
  void publish_progress_if_due();
  // The wait of receive_after and receive_awaiting, once the session knows what wakes it.
  std::optional<ProtocolMessage> wait_and_take(double timeout_s);

  transport::AgentSession& session_;
  std::function<bool(const ProtocolMessage&)> intercept_;
  std::optional<ProgressDigest> progress_;
};

/// Raised by the channel when the coordinator publishes a re-partition for the survivors (an
/// assignment of a newer epoch): every survivor abandons its round and takes over its new
/// block (core/runtime/survivor_takeover.hpp).
class RepartitionRequested : public std::runtime_error {
 public:
  explicit RepartitionRequested(wire::PartitionAssignment a)
      : std::runtime_error("re-partition for the survivors (epoch " + std::to_string(a.epoch()) +
                           ")"),
        assignment(std::move(a)) {}
  wire::PartitionAssignment assignment;
};

/// Takes the coordinator's newest assignment with an epoch above the session's, if any.
std::optional<wire::PartitionAssignment> take_reassignment(transport::AgentSession& session);

/// Takes the coordinator's newest ROLLBACK order with an epoch above the session's (older
/// ones are discarded), if any.
std::optional<RollbackRequested> take_rollback(transport::AgentSession& session);

}  // namespace tessera::agent
