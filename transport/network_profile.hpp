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
  /// How long after sending a sample to a reader the writer ignores that reader's negative
  /// acknowledgements of it, seconds (Fast DDS's nackSupressionDuration, whose default is 0).
  /// Fast DDS 2.9 re-arms this per-reader timer on every send, and re-arming a timer that has
  /// already fired wakes the participant's event thread, which then also fights the writing
  /// thread for the writer's mutex: with 0 that is ~2 wake-ups per write. While the timer still
  /// runs a send does not touch the event thread, so it should outlast the time between two
  /// writes to one reader (a kitti_02 round is ~1.5 ms). Cost: a sample lost on the wire is
  /// repaired up to this much later (shared memory loses none). Range >= 0.
  double nack_suppression_s = 0.05;
};

/// The names --network accepts, in the order --help lists them ("default", "lossy").
std::vector<std::string> network_profile_names();

/// The profile called `name`; throws InputError naming --network and the valid names.
NetworkProfile network_profile(const std::string& name);

}  // namespace tessera::transport
