#pragma once
// Named transport profiles (`--network NAME`): the few Fast DDS transport and reliability
// settings that decide whether a run keeps moving on a bad link. Plain numbers, no Fast DDS
// types (transport/qos.cpp applies them), so the command line can check a name without
// linking Fast DDS. Why each value: docs/dds-runtime.md, "Lossy links".

#include <cstdint>
#include <string>
#include <vector>

namespace tessera::transport {

struct NetworkProfile {
  std::string name;  ///< As given to --network.
  /// Largest RTPS message over UDP (and so the DDS fragment size), bytes. 0 = Fast DDS's
  /// default (65500: one datagram becomes ~45 IP fragments, and losing any one loses it).
  std::uint32_t udp_max_message_size = 0;
  /// UDP socket send and receive buffer sizes, bytes. 0 = the system's default.
  std::uint32_t socket_buffer_bytes = 0;
  /// Reliable writers' heartbeat period, seconds: how soon a reader learns it missed data.
  double heartbeat_period_s = 0.05;
  /// Delay before a writer answers a negative acknowledgement (repair), seconds.
  double nack_response_delay_s = 0.005;
  /// Delay before a reader answers a heartbeat with its acknowledgement, seconds.
  double heartbeat_response_delay_s = 0.005;
};

/// The names --network accepts, in the order --help lists them ("default", "lossy").
std::vector<std::string> network_profile_names();

/// The profile called `name`; throws InputError naming --network and the valid names.
NetworkProfile network_profile(const std::string& name);

}  // namespace tessera::transport
