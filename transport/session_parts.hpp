#pragma once
// What a Session is made of (transport/session.hpp is the public view): its inboxes and the
// pieces that fill and guard them, each in the file named for its concept. Members are
// declared in dependency order (later ones refer to earlier ones). Internal to transport/.

#include <atomic>
#include <cstdint>
#include <string>
#include <tessera/protocol/messages.hpp>
#include <utility>
#include <vector>

#include "tessera.h"
#include "transport/dds_entities.hpp"
#include "transport/dds_trace.hpp"
#include "transport/epoch_routing.hpp"
#include "transport/inbox.hpp"
#include "transport/network_profile.hpp"
#include "transport/peer_tracking.hpp"
#include "transport/readiness.hpp"
#include "transport/run_identity.hpp"
#include "transport/sample_writing.hpp"
#include "transport/session_options.hpp"
#include "transport/status_relay.hpp"

namespace tessera::transport {

struct SessionParts {
  /// `options` must be valid; `domain` is the resolved domain id.
  SessionParts(const SessionOptions& options, int domain);

  SessionOptions opt;  // only shared_memory changes (Session::replace_participant)
  std::vector<std::pair<std::string, std::string>> security;  // participant properties
  std::vector<std::string> former_prefixes;  // replaced participants (ParticipantTags::replaces)
  const NetworkProfile net;                  // network_profile(opt.network)
  const int domain;
  const PeerIdentity me;
  const DdsTrace trace;
  Mailroom room;
  Inbox<wire::AgentAnnouncement> announce_in{room};
  Inbox<wire::PartitionAssignment> assignment_in{room};
  Inbox<wire::MeasurementHandoff> handoff_in{room};
  Inbox<wire::MeasurementHandoff> replica_in{room};  // purpose 1: replicas of peers' data
  Inbox<ProtocolMessage> protocol_in{room};
  Inbox<wire::RoundStatus> status_in{room};
  Inbox<wire::AgentProgress> progress_in{room};
  Inbox<wire::AgentReport> report_in{room};
  Inbox<wire::FinalEstimate> final_in{room};
  Inbox<wire::Control> rejoin_in{room};
  Inbox<wire::Control> rollback_in{room};
  PeerTracker peers;
  Readiness readiness;
  EpochRouter router;
  DdsEntities entities;
  SampleWriter writer;
  // Set once a re-partition renumbered the protocol ids (AgentSession::set_epoch with an id):
  // recipients are then no longer agent ids, so addressed pose blocks go on the shared
  // kBlockTopic (every agent's router picks its own) instead of block_topic_for(recipient).
  bool renumbered = false;
  // The relay agent's collection of round statuses (guarded by room's mutex).
  StatusRelay relay{opt.num_agents};
  bool relay_enabled = false;    // AgentSession::set_round_traffic
  bool rounds_followed = false;  // AgentSession::set_round_traffic
  /// Whether this agent's round statuses go through the relay (status_relay.hpp): agents of
  /// runs of at least kMinAgentsForRelay that enabled it, until a re-partition renumbers the
  /// protocol ids (the relay is agent kRelayAgent, whose id that changes).
  bool relays_statuses() const {
    return relay_enabled && !opt.coordinator && !renumbered && opt.num_agents >= kMinAgentsForRelay;
  }
  // Protocol samples taken by the listeners (SessionStats::protocol_samples_received).
  std::atomic<std::uint64_t> protocol_samples{0};
};

/// The topics the process of `parts.opt`'s role writes and reads, and where each received
/// sample goes (inboxes, epoch routing, READY/FINISHED/ABORT handling). Requires
/// parts.entities to be open. Throws TransportError.
void create_role_endpoints(SessionParts& parts);

}  // namespace tessera::transport
