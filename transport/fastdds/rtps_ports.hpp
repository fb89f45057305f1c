#pragma once
// RTPS's default port mapping (RTPS 2.x, 9.6.1.1: port base, domain gain, participant gain,
// unicast discovery offset; Fast DDS 2.9's PortParameters defaults), without Fast DDS: launch/
// reads it to tell a domain in use, the transport to hold and reach discovery ports
// (discovery_port.hpp).

#include <cstdint>

namespace tessera::transport {

inline constexpr std::uint32_t kRtpsPortBase = 7400;              ///< PB
inline constexpr std::uint32_t kRtpsDomainGain = 250;             ///< DG: ports per domain
inline constexpr std::uint32_t kRtpsParticipantGain = 2;          ///< PG: ports per participant id
inline constexpr std::uint32_t kRtpsUnicastDiscoveryOffset = 10;  ///< d1

/// The first port of `domain`'s range (its multicast discovery port): 7400 + 250 domain.
constexpr std::uint32_t rtps_domain_port_base(int domain) {
  return kRtpsPortBase + kRtpsDomainGain * static_cast<std::uint32_t>(domain);
}

}  // namespace tessera::transport
