#pragma once
// Creates a DDS participant whose UDP discovery does not depend on the domain's discovery
// multicast port being free.
//
// Why: every participant of domain D on a host receives discovery announcements (SPDP) on
// one shared UDP port, 7400 + 250 D. Fast DDS 2.9 binds it with SO_REUSEADDR, so its own
// participants share it, but Linux refuses that bind while any socket without SO_REUSEADDR
// holds the port. From domain 102 on those ports lie in Linux's ephemeral range
// (/proc/sys/net/ipv4/ip_local_port_range, 32768-60999 by default), where every socket bound
// to port 0 -- Fast DDS's own send sockets, DNS look-ups, any program's UDP client -- may get
// one. Fast DDS then only logs a warning that its log level hides and goes on: a participant
// that opens UDPv4 (UDP only, or Fast DDS's built-in UDPv4 + shared memory) discovers nobody
// and is discovered by nobody on this host. Seen in CI as `tessera replay: 0 of 3 readers
// matched after 30.0 s` (online launch on domain 136, ctest -j2); reproduced every time by
// holding port 7400 + 250 D with a plain socket (tests/dds_discovery_port_test.cpp).
// Unicast ports (7410 + 250 D + 2 id, ...) are not the problem: Fast DDS moves on to the next
// participant id when one is taken.
//
// What: just before the participant is created, a socket with SO_REUSEADDR binds the port
// and holds it until Fast DDS has bound it too, so no other program can take it in between.
// If the bind fails (the port is already held without SO_REUSEADDR), the participant keeps
// announcing to the multicast group and also announces by unicast to 127.0.0.1 at the
// discovery ports of the first `local_participants` participant ids of the domain, and a
// one-line warning on stderr names the port and the domain. Participants of this host then
// find each other (every one of them is in the same situation); peers on other hosts still
// hear this participant's multicast announcements, and reach it once they know its unicast
// address, or by --peers.

#include <cstdint>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

namespace tessera::transport {

/// The UDP port on which every participant of `domain` receives discovery announcements
/// sent to the multicast group: 7400 + 250 domain.
std::uint16_t discovery_multicast_port(int domain);

/// Whether a socket with SO_REUSEADDR (as Fast DDS opens it) can bind 0.0.0.0:`port` now:
/// false when another socket holds the port without SO_REUSEADDR.
bool discovery_port_bindable(std::uint16_t port);

/// The unicast discovery port of participant id `id` on `domain`: 7400 + 250 domain + 10 +
/// 2 id.
std::uint32_t discovery_unicast_port(int domain, std::uint32_t id);

/// How many participant ids of this host the unicast fallback reaches for a run of
/// `num_agents` agents: two participants per agent (an online agent has its channel and its
/// stream reader), the coordinator, the replay and tools; at least 32.
std::uint32_t local_discovery_participants(std::uint32_t num_agents);

/// DomainParticipantFactory::create_participant(domain, qos, listener, mask), with the
/// domain's discovery multicast port held for it (see above). A participant without UDPv4
/// (shared memory only) is created unchanged. `local_participants` >= 1: how many
/// participant ids of this host the unicast fallback reaches (0 .. local_participants - 1).
/// Null when Fast DDS refuses the participant, as create_participant.
eprosima::fastdds::dds::DomainParticipant* create_participant_with_discovery_port(
    int domain, eprosima::fastdds::dds::DomainParticipantQos qos,
    eprosima::fastdds::dds::DomainParticipantListener* listener,
    const eprosima::fastdds::dds::StatusMask& mask, std::uint32_t local_participants);

}  // namespace tessera::transport
