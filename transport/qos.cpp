#include "transport/qos.hpp"

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include <algorithm>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <memory>

#include "transport/fastdds/discovery_port.hpp"
#include "transport/fastdds/reader_removal_lock_order.hpp"
#include "transport/topic_names.hpp"

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::Duration_t;

namespace {

// The shared-memory transport. A writer's outgoing samples live in its participant's segment
// until every reader took them: Fast DDS's 512 KB default holds 9 hand-off parts (one
// transport message each, addressed_filter.hpp), so in a large run each agent's ~7,000 parts
// (1M poses, 25 agents) trickled out a few per acknowledgement and the writes timed out. Runs
// above kMaxAgentsWithRecipientTopics agents get 8 MB (pages are taken only as they are used).
std::shared_ptr<eprosima::fastdds::rtps::SharedMemTransportDescriptor> shared_memory_transport(
    std::uint32_t num_agents) {
  auto shm = std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>();
  if (num_agents > kMaxAgentsWithRecipientTopics) shm->segment_size(8u << 20);
  return shm;
}

// The UDP socket buffers: the profile's, else 4 MB above kMaxAgentsWithRecipientTopics agents
// (0 = the system's default, 208 KB here). 64 agents handing off over UDP on one loaded host
// overflowed the default receive buffers: 41 M datagrams dropped in 9 minutes, the
// repairs dropped in turn, and the hand-off never completed.
std::uint32_t socket_buffer_bytes(const NetworkProfile& net, std::uint32_t num_agents) {
  if (net.socket_buffer_bytes != 0) return net.socket_buffer_bytes;
  return num_agents > kMaxAgentsWithRecipientTopics ? 4u << 20 : 0;
}

}  // namespace

void discover_over_udp(dds::DomainParticipantQos& q) {
  namespace rtps = eprosima::fastrtps::rtps;
  rtps::Locator_t unicast;
  unicast.kind = LOCATOR_KIND_UDPv4;
  rtps::IPLocator::setIPv4(unicast, 0, 0, 0, 0);
  unicast.port = 0;
  q.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(unicast);
  rtps::Locator_t multicast;
  multicast.kind = LOCATOR_KIND_UDPv4;
  rtps::IPLocator::setIPv4(multicast, "239.255.0.1");
  multicast.port = 0;
  q.wire_protocol().builtin.metatrafficMulticastLocatorList.push_back(multicast);
}

void udp_transport_only(dds::DomainParticipantQos& q) {
  q.transport().use_builtin_transports = false;
  q.transport().user_transports.push_back(
      std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>());
}

dds::DomainParticipantQos participant_qos(
    const std::string& name, double lease_s, const std::vector<std::string>& initial_peers,
    int domain, std::uint32_t num_agents, const NetworkProfile& net,
    const std::vector<std::pair<std::string, std::string>>& properties, bool shared_memory,
    const std::vector<std::uint8_t>& user_data, bool udp) {
  dds::DomainParticipantQos q;
  dds::DomainParticipantFactory::get_instance()->get_default_participant_qos(q);
  q.name(name);
  if (!user_data.empty()) q.user_data().data_vec(user_data);
  auto& discovery = q.wire_protocol().builtin.discovery_config;
  // Fast DDS's default lease is 20 s (a killed peer noticed after ~18 s); Tessera's 2 s with
  // announcements every lease/5 notices it in ~2 s at negligible cost.
  discovery.leaseDuration = Duration_t(lease_s);
  discovery.leaseDuration_announcementperiod = Duration_t(lease_s / 5.0);
  // Announce a few times quickly at start-up so a missed first announcement costs
  // ~0.1 s instead of a full announcement period.
  discovery.initial_announcements.count = 5;
  discovery.initial_announcements.period = Duration_t(0, 100000000);
  if (shared_memory && !udp) {
    // Shared memory only: every peer is on this host. Fast DDS then also announces and
    // discovers over shared-memory ports (its SHM transport has multicast-like ports that
    // every participant of the domain opens), and creates no UDP socket, receive thread or
    // interface list. Peers at --peers addresses are unreachable (SessionOptions::validate).
    q.transport().use_builtin_transports = false;
    q.transport().user_transports.push_back(shared_memory_transport(num_agents));
  } else if (net.udp_max_message_size != 0 || socket_buffer_bytes(net, num_agents) != 0 ||
             !shared_memory) {
    // Our own UDPv4 transport instead of the built-in one, plus shared memory as built in
    // (same-host peers keep using it) unless `shared_memory` is off. Fast DDS fragments every
    // sample to the smallest maximum message size of the participant's transports.
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    if (net.udp_max_message_size != 0) udp->maxMessageSize = net.udp_max_message_size;
    const std::uint32_t buffer = socket_buffer_bytes(net, num_agents);
    udp->sendBufferSize = buffer;
    udp->receiveBufferSize = buffer;
    q.transport().use_builtin_transports = false;
    if (shared_memory) q.transport().user_transports.push_back(shared_memory_transport(num_agents));
    q.transport().user_transports.push_back(udp);
    q.transport().send_socket_buffer_size = buffer;
    q.transport().listen_socket_buffer_size = buffer;
  }
  if (shared_memory && udp) discover_over_udp(q);
  for (const auto& [key, value] : properties) q.properties().properties().emplace_back(key, value);
  for (const std::string& ip : initial_peers) {
    // Metatraffic unicast port of participant id p (fastdds/discovery_port.hpp).
    // + 3: the coordinator and tools; + 3 more: participants re-created by
    // Session::replace_participant, which briefly overlap the ones they replace.
    const std::uint32_t participants = num_agents + 6;
    for (std::uint32_t p = 0; p < participants; ++p) {
      eprosima::fastrtps::rtps::Locator_t loc;
      eprosima::fastrtps::rtps::IPLocator::setIPv4(loc, ip);
      loc.port = discovery_unicast_port(domain, p);
      q.wire_protocol().builtin.initialPeersList.push_back(loc);
    }
  }
  return q;
}

dds::PublisherQos publisher_qos(const std::string& run_id) {
  dds::PublisherQos q = dds::PUBLISHER_QOS_DEFAULT;
  q.partition().push_back(run_id.c_str());
  return q;
}

dds::SubscriberQos subscriber_qos(const std::string& run_id) {
  dds::SubscriberQos q = dds::SUBSCRIBER_QOS_DEFAULT;
  q.partition().push_back(run_id.c_str());
  return q;
}

dds::DataWriterQos writer_qos(bool handshake, double lease_s, std::uint32_t num_agents,
                              const NetworkProfile& net, bool liveliness, bool waited_for) {
  dds::DataWriterQos q = dds::DATAWRITER_QOS_DEFAULT;
  // Room to filter for every agent's reader on the writer's side (addressed_filter.hpp):
  // Fast DDS's default of 32 would leave the readers past it to filter for themselves.
  q.writer_resource_limits().reader_filters_allocation.maximum = num_agents + 8;
  q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  // write() never blocks long: when the bounded history is full it returns and we retry
  // after waiting for acknowledgements (Session::Impl::write).
  q.reliability().max_blocking_time = Duration_t(0, 10000000);
  // TRANSIENT_LOCAL for every topic: on the hand-shake topics so late joiners get what was
  // written; on the others (whose readers are VOLATILE, so they get only what is written after
  // they matched) so that Fast DDS 2.9.1 never removes acknowledged samples while a reader
  // leaves, which could hang the process (fastdds/reader_removal_lock_order.hpp).
  keep_acknowledged_samples(q);
  // Bounded KEEP_ALL: unbounded limits let acknowledged samples pile up (hundreds of MB).
  q.history().kind = dds::KEEP_ALL_HISTORY_QOS;
  const std::int32_t history = handshake ? kWriterHistory : kVolatileWriterHistory;
  q.resource_limits().max_samples = history;
  q.resource_limits().max_instances = 1;
  q.resource_limits().max_samples_per_instance = history;
  q.resource_limits().allocated_samples = 4;
  // The default 3 s heartbeat stalls request/reply exchanges for seconds after a loss.
  // The hand-off writers of small runs are waited for like the hand-shake topics' (qos.hpp).
  const bool awaited = handshake || (waited_for && num_agents <= kMaxAgentsWithRecipientTopics);
  q.reliable_writer_qos().times.heartbeatPeriod = Duration_t(
      awaited ? std::min(net.heartbeat_period_s, kHandshakeHeartbeatS) : net.heartbeat_period_s);
  q.reliable_writer_qos().times.nackResponseDelay = Duration_t(net.nack_response_delay_s);
  // Not Fast DDS's 0 on the volatile (per-round) topics: NetworkProfile::nack_suppression_s.
  // The hand-shake topics are written a few times a run and keep answering at once; so do the
  // hand-off writers of small runs, written in one burst (a part lost there was repaired only
  // after the 50 ms window: city10000's agent 0 then waited 36-51 ms for its acknowledgement).
  q.reliable_writer_qos().times.nackSupressionDuration =
      Duration_t(awaited ? 0.0 : net.nack_suppression_s);
  q.liveliness().kind = dds::AUTOMATIC_LIVELINESS_QOS;
  q.liveliness().lease_duration =
      liveliness ? Duration_t(lease_s) : eprosima::fastrtps::c_TimeInfinite;
  q.liveliness().announcement_period =
      liveliness ? Duration_t(lease_s / 4.0) : eprosima::fastrtps::c_TimeInfinite;
  // Messages are variable-sized (unbounded sequences): size payloads per sample.
  q.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return q;
}

dds::DataReaderQos reader_qos(bool transient_local, double lease_s, std::uint32_t num_agents,
                              const NetworkProfile& net, bool liveliness) {
  dds::DataReaderQos q = dds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind =
      transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = dds::KEEP_ALL_HISTORY_QOS;
  // The listener takes every sample at once; room for a burst from every writer avoids
  // rejections (and their heartbeat-period resend delay) when all agents send together.
  const std::int32_t limit =
      std::max<std::int32_t>(kWriterHistory, 4 * static_cast<std::int32_t>(num_agents));
  q.resource_limits().max_samples = limit;
  q.resource_limits().max_instances = 1;
  q.resource_limits().max_samples_per_instance = limit;
  q.resource_limits().allocated_samples = 4;
  q.reliable_reader_qos().times.heartbeatResponseDelay = Duration_t(net.heartbeat_response_delay_s);
  // A hand-shake sample that reaches this process before its writer is matched (endpoint
  // discovery races the first write of a TRANSIENT_LOCAL writer) is dropped; in launch traces it
  // came again 70 ms after the match, at the reader's first acknowledgement (Fast DDS's default
  // delay): an agent's announcement, on the critical path of the launch.
  if (transient_local)
    q.reliable_reader_qos().times.initialAcknackDelay =
        Duration_t(std::min(net.heartbeat_period_s, kHandshakeHeartbeatS));
  q.liveliness().kind = dds::AUTOMATIC_LIVELINESS_QOS;
  q.liveliness().lease_duration =
      liveliness ? Duration_t(lease_s) : eprosima::fastrtps::c_TimeInfinite;
  q.endpoint().history_memory_policy =
      eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  return q;
}

}  // namespace tessera::transport
