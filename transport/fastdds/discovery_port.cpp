#include "transport/fastdds/discovery_port.hpp"

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <iostream>
#include <string>

#include "transport/fastdds/intraprocess_builtin.hpp"
#include "transport/fastdds/rtps_ports.hpp"

namespace tessera::transport {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {

// Fast DDS's default discovery multicast group.
constexpr const char* kDiscoveryGroup = "239.255.0.1";

// A socket bound like Fast DDS binds the discovery multicast port (0.0.0.0, SO_REUSEADDR);
// closed on destruction. `bound` false: the bind failed (errno in `error`).
struct ReusableBind {
  int fd = -1;
  bool bound = false;
  int error = 0;
  explicit ReusableBind(std::uint16_t port) {
    fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
      error = errno;
      return;
    }
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_ANY);
    bound = ::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
    if (!bound) error = errno;
  }
  ~ReusableBind() {
    if (fd >= 0) ::close(fd);
  }
  ReusableBind(const ReusableBind&) = delete;
  ReusableBind& operator=(const ReusableBind&) = delete;
};

// Whether the participant opens a UDPv4 transport: Fast DDS's built-in transports (UDPv4 and
// shared memory), or a UDPv4 descriptor among its own.
bool opens_udpv4(const dds::DomainParticipantQos& qos) {
  if (qos.transport().use_builtin_transports) return true;
  const auto& transports = qos.transport().user_transports;
  return std::any_of(transports.begin(), transports.end(), [](const auto& t) {
    return dynamic_cast<const eprosima::fastdds::rtps::UDPv4TransportDescriptor*>(t.get()) !=
           nullptr;
  });
}

void add_peer(rtps::LocatorList_t& peers, const char* ip, std::uint32_t port) {
  rtps::Locator_t locator;
  rtps::IPLocator::setIPv4(locator, ip);
  locator.port = port;
  if (std::find(peers.begin(), peers.end(), locator) == peers.end()) peers.push_back(locator);
}

// The unicast fallback: keep announcing to the multicast group (what Fast DDS does without
// initial peers), and announce to this host's first `count` participant ids by unicast.
void add_local_discovery_peers(dds::DomainParticipantQos& qos, int domain, std::uint32_t count) {
  rtps::LocatorList_t& peers = qos.wire_protocol().builtin.initialPeersList;
  if (peers.empty()) add_peer(peers, kDiscoveryGroup, discovery_multicast_port(domain));
  for (std::uint32_t id = 0; id < count; ++id)
    add_peer(peers, "127.0.0.1", discovery_unicast_port(domain, id));
}

}  // namespace

std::uint16_t discovery_multicast_port(int domain) {
  return static_cast<std::uint16_t>(rtps_domain_port_base(domain));
}

std::uint32_t discovery_unicast_port(int domain, std::uint32_t id) {
  return rtps_domain_port_base(domain) + kRtpsUnicastDiscoveryOffset + kRtpsParticipantGain * id;
}

std::uint32_t local_discovery_participants(std::uint32_t num_agents) {
  return std::max<std::uint32_t>(32, 2 * num_agents + 8);
}

bool discovery_port_bindable(std::uint16_t port) {
  return ReusableBind(port).bound;
}

dds::DomainParticipant* create_participant_with_discovery_port(
    int domain, dds::DomainParticipantQos qos, dds::DomainParticipantListener* listener,
    const dds::StatusMask& mask, std::uint32_t local_participants) {
  keep_builtin_traffic_off_intraprocess();  // before any participant (intraprocess_builtin.hpp)
  auto* factory = dds::DomainParticipantFactory::get_instance();
  if (!opens_udpv4(qos)) return factory->create_participant(domain, qos, listener, mask);
  const std::uint16_t port = discovery_multicast_port(domain);
  // Held until Fast DDS has bound the port as well (both with SO_REUSEADDR).
  const ReusableBind hold(port);
  if (!hold.bound && hold.error == EADDRINUSE) {
    const std::uint32_t count = std::max<std::uint32_t>(local_participants, 1);
    add_local_discovery_peers(qos, domain, count);
    static std::atomic<bool> warned{false};
    if (!warned.exchange(true))
      std::cerr << "warning: UDP port " << port << " (discovery multicast port of DDS domain "
                << domain << ": 7400 + 250 x " << domain
                << ") is held by another program without SO_REUSEADDR; participant '"
                << qos.name().to_string()
                << "' finds the participants of this host by unicast to 127.0.0.1 instead "
                   "(participant ids 0.."
                << count - 1
                << "); peers on other hosts may need --peers (or use another --domain)\n";
  }
  return factory->create_participant(domain, qos, listener, mask);
}

}  // namespace tessera::transport
