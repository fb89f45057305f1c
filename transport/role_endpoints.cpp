// create_role_endpoints (session_parts.hpp): which topics the coordinator and the agents
// write and read, with what durability, which peers each must match before the readiness
// barrier, and where each received sample goes.

#include "tesseraPubSubTypes.h"
#include "transport/message_mapping.hpp"
#include "transport/riding_blocks.hpp"
#include "transport/session_parts.hpp"
#include "transport/status_relay.hpp"
#include "transport/topic_names.hpp"

namespace tessera::transport {

namespace {

// Control: everyone reads everyone (READY barrier, ABORT, FINISHED, REJOIN, ROLLBACK).
void dispatch_control(SessionParts& s, wire::Control&& m) {
  PeerIdentity from{s.opt.run_id, m.sender() == kCoordinatorId,
                    m.sender() == kCoordinatorId ? 0u : m.sender()};
  switch (m.kind()) {
    case wire::CONTROL_READY:
      s.readiness.on_ready(from);
      break;
    case wire::CONTROL_FINISHED:
      s.readiness.on_finished();
      break;
    case wire::CONTROL_ABORT: {
      // `agent` names the process whose failure started the abort, whoever relays it, so
      // the first ABORT to arrive (own or relayed) gives the true cause.
      const PeerIdentity origin{s.opt.run_id, m.agent() == kCoordinatorId,
                                m.agent() == kCoordinatorId ? 0u : m.agent()};
      std::string why = origin.describe() + " aborted run '" + s.opt.run_id + "': " + m.reason();
      if (origin.describe() != from.describe()) why += " (relayed by " + from.describe() + ")";
      s.readiness.on_abort(from);
      s.room.request_stop(StopInfo{1, why, true, m.agent(), m.reason()});
      break;
    }
    case wire::CONTROL_REJOIN:
      if (s.opt.coordinator) s.rejoin_in.push(std::move(m));
      break;
    case wire::CONTROL_ROLLBACK:
      if (!s.opt.coordinator && m.sender() == kCoordinatorId) s.rollback_in.push(std::move(m));
      break;
  }
}

void create_coordinator_endpoints(SessionParts& s) {
  DdsEntities& e = s.entities;
  e.make_writer<wire::PartitionAssignmentPubSubType>(kAssignmentTopic, true, Expect::kNone);
  e.make_writer<wire::ControlPubSubType>(kControlTopic, true, Expect::kNone);
  e.make_reader<wire::AgentAnnouncementPubSubType, wire::AgentAnnouncement>(
      kAnnounceTopic, true, Expect::kNone,
      [&s](wire::AgentAnnouncement&& m) { s.announce_in.push(std::move(m)); });
  e.make_reader<wire::RoundStatusPubSubType, wire::RoundStatus>(
      kStatusTopic, false, Expect::kAllAgents, [&s](wire::RoundStatus&& m) {
        if (m.bundle().empty()) {
          s.status_in.push(std::move(m));
          return;
        }
        for (auto& one : StatusRelay::unpack(m)) s.status_in.push(std::move(one));  // relayed
      });
  e.make_reader<wire::FinalEstimatePubSubType, wire::FinalEstimate>(
      kFinalTopic, false, Expect::kAllAgents,
      [&s](wire::FinalEstimate&& m) { s.final_in.push(std::move(m)); });
  e.make_reader<wire::AgentProgressPubSubType, wire::AgentProgress>(
      kProgressTopic, false, Expect::kAllAgents,
      [&s](wire::AgentProgress&& m) { s.progress_in.push(std::move(m)); });
  e.make_reader<wire::AgentReportPubSubType, wire::AgentReport>(
      kReportTopic, false, Expect::kAllAgents,
      [&s](wire::AgentReport&& m) { s.report_in.push(std::move(m)); });
}

void create_agent_endpoints(SessionParts& s) {
  DdsEntities& e = s.entities;
  const std::uint32_t me = s.me.agent_id;
  e.make_writer<wire::AgentAnnouncementPubSubType>(kAnnounceTopic, true, Expect::kNone);
  e.make_writer<wire::ControlPubSubType>(kControlTopic, true, Expect::kNone);
  e.make_writer<wire::MeasurementHandoffPubSubType>(kHandoffTopic, false, Expect::kOtherAgents);
  e.make_writer<wire::MeasurementHandoffPubSubType>(kAddressedHandoffTopic, false,
                                                    Expect::kOtherAgents);
  // Broadcast pose blocks on kBlockTopic.
  e.make_writer<wire::PoseBlockPubSubType>(kBlockTopic, false, Expect::kOtherAgents);
  const bool recipient_topics = s.opt.num_agents <= kMaxAgentsWithRecipientTopics;
  // Addressed ones: on the recipient's own topic, or one filtered topic in a large run.
  if (recipient_topics) {
    for (std::uint32_t k = 0; k < s.opt.num_agents; ++k)
      if (k != me)
        e.make_writer<wire::PoseBlockPubSubType>(block_topic_for(k), false, Expect::kAgent, k);
  } else {
    e.make_writer<wire::PoseBlockPubSubType>(kAddressedBlockTopic, false, Expect::kOtherAgents);
  }
  // Statuses the coordinator reads (coordinator_reads_status) on kStatusTopic, the others on
  // kAgentStatusTopic; its progress digests on kProgressTopic, agent 0's reports on
  // kReportTopic (every agent writes it: after a re-partition another agent may be agent 0).
  e.make_writer<wire::RoundStatusPubSubType>(kStatusTopic, false,
                                             Expect::kOtherAgentsAndCoordinator);
  e.make_writer<wire::RoundStatusPubSubType>(kAgentStatusTopic, false, Expect::kOtherAgents);
  e.make_writer<wire::AgentProgressPubSubType>(kProgressTopic, false, Expect::kCoordinator);
  e.make_writer<wire::AgentReportPubSubType>(kReportTopic, false, Expect::kCoordinator);
  // Round statuses through the relay (status_relay.hpp): the others write to it, it reads.
  const bool relayed = s.opt.num_agents >= kMinAgentsForRelay;
  if (relayed && me != kRelayAgent)
    e.make_writer<wire::RoundStatusPubSubType>(kRelayStatusTopic, false, Expect::kAgent,
                                               kRelayAgent);
  e.make_writer<wire::FinalEstimatePubSubType>(kFinalTopic, false, Expect::kCoordinator);
  e.make_reader<wire::PartitionAssignmentPubSubType, wire::PartitionAssignment>(
      kAssignmentTopic, true, Expect::kNone,
      [&s](wire::PartitionAssignment&& m) { s.assignment_in.push(std::move(m)); });
  auto deliver_handoff = [&s, me](wire::MeasurementHandoff&& m) {
    if (m.recipient() != me || m.sender() == me) return;
    if (m.purpose() == 1)
      s.replica_in.push(std::move(m));
    else
      s.handoff_in.push(std::move(m));
  };
  e.make_reader<wire::MeasurementHandoffPubSubType, wire::MeasurementHandoff>(
      kHandoffTopic, false, Expect::kOtherAgents, deliver_handoff);
  e.make_reader<wire::MeasurementHandoffPubSubType, wire::MeasurementHandoff>(
      kAddressedHandoffTopic, false, Expect::kOtherAgents, deliver_handoff,
      AddressedLayout::kHandoff, me);
  auto deliver_block = [&s](wire::PoseBlock&& m) {
    ++s.protocol_samples;
    s.router.deliver(m.epoch(), m.sender(), m.broadcast(), m.recipients(),
                     ProtocolMessage(from_wire(m)));
  };
  e.make_reader<wire::PoseBlockPubSubType, wire::PoseBlock>(kBlockTopic, false,
                                                            Expect::kOtherAgents, deliver_block);
  if (recipient_topics)
    e.make_reader<wire::PoseBlockPubSubType, wire::PoseBlock>(block_topic_for(me), false,
                                                              Expect::kOtherAgents, deliver_block);
  else
    e.make_reader<wire::PoseBlockPubSubType, wire::PoseBlock>(kAddressedBlockTopic, false,
                                                              Expect::kOtherAgents, deliver_block,
                                                              AddressedLayout::kBlock, me);
  for (const char* topic : {kStatusTopic, kAgentStatusTopic})
    e.make_reader<wire::RoundStatusPubSubType, wire::RoundStatus>(
        topic, false, Expect::kOtherAgents, [&s](wire::RoundStatus&& m) {
          ++s.protocol_samples;
          if (!m.bundle().empty()) {
            // A relay's bundle: every agent's status of one step (ours is dropped by the
            // router); the relay's own copy of its bundle is not for it.
            if (m.sender() == s.router.protocol_id()) return;
            for (const auto& one : StatusRelay::unpack(m))
              s.router.deliver(one.epoch(), one.sender(), true, {},
                               ProtocolMessage(from_wire(one)));
            return;
          }
          s.router.deliver(m.epoch(), m.sender(), m.broadcast(), m.recipients(),
                           ProtocolMessage(from_wire(m)));
        });
  if (relayed && me == kRelayAgent)
    e.make_reader<wire::RoundStatusPubSubType, wire::RoundStatus>(
        kRelayStatusTopic, false, Expect::kOtherAgents, [&s](wire::RoundStatus&& m) {
          ++s.protocol_samples;
          // The sender's blocks for us that rode with its status (Session::send_all): as if
          // they had come on our block topic, and not kept by the relay with the status.
          for (auto& b : detach_blocks(m))
            s.router.deliver(m.epoch(), m.sender(), false, {kRelayAgent},
                             ProtocolMessage(std::move(b)));
          s.room.with_lock([&] { return s.relay.add(m, s.router.epoch_locked()); });
          s.router.deliver(m.epoch(), m.sender(), m.broadcast(), m.recipients(),
                           ProtocolMessage(from_wire(m)));
        });
}

}  // namespace

void create_role_endpoints(SessionParts& s) {
  if (s.opt.coordinator)
    create_coordinator_endpoints(s);
  else
    create_agent_endpoints(s);
  const std::uint32_t self_id = s.opt.coordinator ? kCoordinatorId : s.me.agent_id;
  s.entities.make_reader<wire::ControlPubSubType, wire::Control>(
      kControlTopic, true, Expect::kNone, [&s, self_id](wire::Control&& m) {
        if (m.sender() == self_id) return;
        dispatch_control(s, std::move(m));
      });
}

}  // namespace tessera::transport
