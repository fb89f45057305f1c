#pragma once
// The DDS topics of the message types (Partition QoS = run id on top). Round statuses and
// pose blocks use several topics each, so that a message reaches only the processes that
// need it (docs/dds-runtime.md, "Who receives what"). All start with "tessera_": the
// permissions of scripts/security/make_identities.sh grant "tessera_*". Shared by the session
// and the tools that watch a run (tessera-dds-snoop).

#include <cstdint>
#include <string>

namespace tessera::transport {

inline constexpr const char* kAnnounceTopic = "tessera_announce";
inline constexpr const char* kAssignmentTopic = "tessera_assignment";
inline constexpr const char* kHandoffTopic = "tessera_handoff";
/// The parts of the hand-offs (purpose 0), read through a content filter on the recipient
/// (addressed_filter.hpp): each agent receives only its own. kHandoffTopic carries the rest
/// (replicas and take-over hand-offs: large samples, which Fast DDS 2.9 cannot filter on the
/// writer's side when they are sent in fragments).
inline constexpr const char* kAddressedHandoffTopic = "tessera_handoff_addressed";
inline constexpr const char* kBlockTopic = "tessera_pose_block";
/// Pose blocks addressed by agent id in runs of more than kMaxAgentsWithRecipientTopics agents
/// (before any renumbering re-partition): one topic, read through a filter on the recipients.
inline constexpr const char* kAddressedBlockTopic = "tessera_pose_block_addressed";
inline constexpr const char* kStatusTopic = "tessera_round_status";
inline constexpr const char* kFinalTopic = "tessera_final";
inline constexpr const char* kControlTopic = "tessera_control";
/// Round statuses only agents need (rounding reductions, the initialisation stage,
/// certification): kept off kStatusTopic so the coordinator is not woken by each of them.
inline constexpr const char* kAgentStatusTopic = "tessera_agent_status";
/// Round statuses on their way to the relay agent, the topic's only reader
/// (transport/status_relay.hpp); the relay sends them on as bundles on kStatusTopic.
inline constexpr const char* kRelayStatusTopic = "tessera_status_relay";
/// The agents' progress digests (wire::AgentProgress), read by the coordinator only: a few
/// samples a second per agent instead of every round status (agent/progress_digest.hpp).
inline constexpr const char* kProgressTopic = "tessera_agent_progress";
/// Agent 0's reports (wire::AgentReport: set-up times, stage progress, certificate, robust
/// decisions, phase times, the final report), read by the coordinator only.
inline constexpr const char* kReportTopic = "tessera_agent_report";

/// Whether a round status of this phase is one of core's round statuses of the solve
/// (ProtocolPhase::kStatus = 1, and kRedoStatus = 5 after a momentum restart;
/// core/include/tessera/distributed/round_protocol.hpp): the ones the coordinator follows for
/// progress and loss handling, and the ones the status relay bundles.
inline bool is_solve_status_phase(std::uint32_t phase) {
  return phase == 1 || phase == 5;
}

/// Whether the coordinator reads round statuses of this phase (they go on kStatusTopic, the
/// others on kAgentStatusTopic): core's round statuses of the solve (phase 1, and 5 after a
/// restart; coordinator/round_reports.hpp's is_round_status) only when `rounds_followed`: while
/// the coordinator arbitrates lost agents (rejoin, replicas), whose rollback round and lag
/// checks need each agent's own latest round. Otherwise it follows the agents' progress digests
/// (kProgressTopic) and is not woken by the N statuses of every round. Agent 0's reports have
/// their own topic (kReportTopic).
inline bool coordinator_reads_status(std::uint32_t phase, bool rounds_followed) {
  return rounds_followed && is_solve_status_phase(phase);
}

/// Runs of at most this many agents use block_topic_for(k); larger ones send addressed blocks on
/// kAddressedBlockTopic, which each agent reads through a content filter on the recipients
/// (addressed_filter.hpp). Each agent writes every other agent's topic, so endpoints grow as N^2:
/// at N = 25 (600 more writers) the discovery burst on 2 cores delayed participant
/// announcements until a participant lease expired during set-up.
inline constexpr std::uint32_t kMaxAgentsWithRecipientTopics = 8;

/// Pose blocks addressed to agent `k` alone (kBlockTopic carries the broadcast ones): only
/// the recipient's process receives them, instead of every agent receiving and dropping them.
inline std::string block_topic_for(std::uint32_t k) {
  return std::string(kBlockTopic) + "_to_" + std::to_string(k);
}

/// The topics of the per-round traffic (pose blocks and round statuses, every kind), the
/// progress digests and agent 0's reports: many small samples a second (the reports: a few a
/// run, on a status topic before they had their own), so their endpoints carry no liveliness
/// lease (qos.hpp; every process's control writer has one).
inline bool is_round_topic(const std::string& name) {
  return name.rfind(kBlockTopic, 0) == 0 || name == kStatusTopic || name == kAgentStatusTopic ||
         name == kRelayStatusTopic || name == kProgressTopic || name == kReportTopic;
}

/// The hand-off topics: written in one burst at set-up (and for replicas and take-overs), whose
/// writer waits for its parts to be acknowledged every few parts (agent/handoff_exchange.cpp).
inline bool is_handoff_topic(const std::string& name) {
  return name == kHandoffTopic || name == kAddressedHandoffTopic;
}

}  // namespace tessera::transport
