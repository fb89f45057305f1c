#pragma once
// The QoS of every DDS entity of the runtime, in one place (see docs/dds-runtime.md for
// why each value). Internal to transport/ (dds_entities.hpp).

#include <cstdint>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <string>
#include <utility>
#include <vector>

#include "transport/network_profile.hpp"

namespace tessera::transport {

/// Samples a writer may hold unacknowledged before write() has to wait (bounded KEEP_ALL),
/// for the hand-shake topics (TRANSIENT_LOCAL: they keep what they wrote for late joiners).
constexpr std::int32_t kWriterHistory = 16;
/// The same for the topics with VOLATILE readers (pose blocks, statuses, hand-offs, finals),
/// whose writers are TRANSIENT_LOCAL too (fastdds/reader_removal_lock_order.hpp). Readers
/// acknowledge only when a heartbeat asks (every heartbeat period, 50 ms by default), so
/// a writer sending faster than kWriterHistory samples per heartbeat period stalled in
/// write() until the next acknowledgement (measured: 5 agents broadcasting one status per
/// step, 3-4% of the writes waited > 10 ms; mean step 2.4-3.0 ms -> 1.3-1.5 ms with 64). Such
/// a writer drops the oldest acknowledged sample when a write needs room, and its writing
/// thread drops all of them once acknowledged, every kDropAcknowledgedEvery writes
/// (acknowledged_drop.hpp): the bound is for samples in flight, not kept. 256 because the
/// distributed rounding writes one status per message step (~0.85 ms on 2 cores), ~59 per
/// heartbeat period, and 64 filled at times (every agent's status writer at once, each write()
/// then blocked for its 10 ms max_blocking_time and retried); 256 holds 50 ms of messages at
/// 0.2 ms.
constexpr std::int32_t kVolatileWriterHistory = 256;
/// Heartbeat period of the TRANSIENT_LOCAL writers (seconds, at most; the profile's period
/// when shorter): they write a handful of samples per run (READY, ABORT, FINISHED, the
/// assignment), and waiting for those to be acknowledged (Session::flush, the linger before
/// leaving on an error) lasts until the next heartbeat. Heartbeats only go out while samples
/// are unacknowledged, so a short period costs nothing between those writes.
constexpr double kHandshakeHeartbeatS = 0.005;

/// Discovery (SPDP, SEDP) over UDPv4 only, at Fast DDS's default ports and addresses, for a
/// participant that also has shared memory (which then carries user data between processes of
/// one host, as before). Why: a Fast DDS 2.9 shared-memory listener whose first message from a
/// peer arrives after that peer deleted its participant stops receiving for good
/// (fastdds/shm_receive_watch.hpp), and a deleted participant's last messages are discovery
/// messages, sent to every participant of the domain, other runs' too. Two runs on one domain,
/// 30 runs started 0.2 s apart (scripts/dds_staggered_runs.sh 118 30 0.2, load 16-28): 6 and 12
/// of 30 failed with discovery over shared memory, 0, 0 and 0 of 30 with this.
void discover_over_udp(eprosima::fastdds::dds::DomainParticipantQos& qos);

/// UDPv4 only, discovery and data (no shared memory), for the participants of the online runs
/// (the online channel, the graph stream), whose processes come and go while others run: a
/// killed agent, one started again with its id, a late joiner, a replay that ends. Both
/// shared-memory defects above hit exactly those: a port left locked by a process killed while
/// writing into it, and a listener stalled for good by a peer that deleted its participant
/// before the listener read its first message. Seen once in a full `ctest -j2`: an agent
/// started again after a take-over heard nothing for 90 s, and the survivors' reliable writes
/// to it waited until they failed, ending the run.
void udp_transport_only(eprosima::fastdds::dds::DomainParticipantQos& qos);

/// Participant: named, short lease so a dead peer is noticed within ~lease seconds,
/// optional unicast initial peers (participant ids 0..num_agents + 5 on `domain`),
/// the UDP datagram size and socket buffers of `net`, extra `properties` (DDS Security's,
/// security.hpp).
/// `shared_memory` false: UDPv4 only (also between processes of one host). Used by runs that
/// survive SIGKILLed processes: a process killed while writing into a peer's shared-memory
/// port leaves that port locked, and the peer then hears nothing more (seen as every agent
/// "lost" at once, or a restarted agent that never gets its messages).
/// `user_data`: the participant's USER_DATA (ParticipantTags::encode(), participant_tags.hpp).
/// `udp` false (with `shared_memory`): shared memory only (SessionOptions::transport "shm"):
/// discovery and data over shared-memory ports, no UDP sockets or their receive threads.
/// Both (the default): discovery over UDP, data over shared memory (discover_over_udp).
eprosima::fastdds::dds::DomainParticipantQos participant_qos(
    const std::string& name, double lease_s, const std::vector<std::string>& initial_peers,
    int domain, std::uint32_t num_agents, const NetworkProfile& net,
    const std::vector<std::pair<std::string, std::string>>& properties = {},
    bool shared_memory = true, const std::vector<std::uint8_t>& user_data = {}, bool udp = true);
/// Publisher / subscriber: Partition = run id.
eprosima::fastdds::dds::PublisherQos publisher_qos(const std::string& run_id);
eprosima::fastdds::dds::SubscriberQos subscriber_qos(const std::string& run_id);
/// Reliable, bounded KEEP_ALL, heartbeat and repair delays of `net`, AUTOMATIC liveliness
/// with `lease_s` (`liveliness` false: no liveliness lease at all).
/// `handshake` / `transient_local`: a hand-shake topic (written a few times a run: a short
/// history, a short heartbeat, no NACK suppression). Writers are TRANSIENT_LOCAL on every topic
/// (fastdds/reader_removal_lock_order.hpp); readers are TRANSIENT_LOCAL on the hand-shake topics
/// (late joiners still get them), VOLATILE otherwise (they get only what is written after they
/// matched).
///
/// The per-round topics (pose blocks, round statuses) use `liveliness` false: with a lease,
/// Fast DDS 2.9 asserts the writer's liveliness on every write and the reader's on every
/// sample received, and each assertion restarts a timer of the participant's event thread,
/// i.e. wakes that thread (measured: about a third of all context switches of a run, ~50 per
/// round over 6 processes). A dead peer is still noticed by the participant lease and by the
/// liveliness of its set-up topics' writers (control, announcement, ...), which stay AUTOMATIC
/// and are asserted by the participant's periodic liveliness messages.
///
/// `waited_for`: a writer whose application waits for its samples to be acknowledged between
/// bursts (the hand-off's parts): in runs of up to kMaxAgentsWithRecipientTopics agents it gets
/// the hand-shake heartbeat and no NACK suppression, since a reader acknowledges only when a
/// heartbeat asks and each wait otherwise lasted until the next 50 ms heartbeat (city10000, 5
/// agents: agent 0 waited 50-110 ms twice while handing off its 39 parts, on the run's critical
/// path). Larger runs keep the profile's period: every heartbeat asks every matched reader for an
/// acknowledgement, so its traffic grows as N^2 while a burst is unacknowledged.
eprosima::fastdds::dds::DataWriterQos writer_qos(bool handshake, double lease_s,
                                                 std::uint32_t num_agents,
                                                 const NetworkProfile& net, bool liveliness = true,
                                                 bool waited_for = false);
/// Readers of the hand-shake topics (`transient_local`) send their first acknowledgement after
/// kHandshakeHeartbeatS instead of Fast DDS's 70 ms (qos.cpp says why).
eprosima::fastdds::dds::DataReaderQos reader_qos(bool transient_local, double lease_s,
                                                 std::uint32_t num_agents,
                                                 const NetworkProfile& net, bool liveliness = true);

}  // namespace tessera::transport
