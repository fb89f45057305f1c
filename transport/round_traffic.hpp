#pragma once
// How an agent's round statuses travel during the solve: a choice every agent of a run makes
// alike, once, before its first round status (AgentSession::set_round_traffic). Defaults are
// all to all, and the coordinator follows the agents' progress digests instead of the rounds.

namespace tessera::transport {

struct RoundTraffic {
  /// Round statuses through the relay agent (transport/status_relay.hpp: 2N - 1 deliveries a
  /// step instead of N^2) in runs of at least kMinAgentsForRelay agents; pose blocks of the
  /// solve addressed to the relay then ride in the sender's status sample
  /// (transport/riding_blocks.hpp). Off where the coordinator arbitrates lost agents: it then
  /// reads each agent's round from its own status.
  bool status_relay = false;
  /// Whether core's round statuses of the solve (and the relay's bundles) also go to the
  /// coordinator (topic_names.hpp, coordinator_reads_status): on while it arbitrates lost
  /// agents (rejoin, replicas); off it follows the agents' progress digests.
  bool coordinator_follows_rounds = false;
};

}  // namespace tessera::transport
