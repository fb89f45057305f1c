#include "transport/network_profile.hpp"

#include <tessera/util/input_error.hpp>

namespace tessera::transport {

std::vector<std::string> network_profile_names() {
  return {"default", "lossy"};
}

NetworkProfile network_profile(const std::string& name) {
  NetworkProfile p;
  p.name = name;
  if (name == "default") return p;  // Fast DDS's transports; QoS of docs/dds-runtime.md
  if (name == "lossy") {
    // One RTPS message per Ethernet frame: a lost frame then costs one fragment, repaired
    // on its own, instead of the whole 64 KB datagram (which with 10% frame loss almost
    // never arrives whole).
    p.udp_max_message_size = 1400;
    // Room for a burst of small datagrams (a 1 MB sample is ~750 of them).
    p.socket_buffer_bytes = 4u << 20;
    // A lost fragment is only noticed at the writer's next heartbeat, and the round
    // protocol waits for it: 10 ms instead of 50 ms, and no added delay before the reader's
    // negative acknowledgement or the writer's repair. Measured (3 agents in namespaces,
    // 10% loss on one link, 1000-pose grid): 50 ms/5 ms 16.8 s, 10 ms/0 7.9 s, loss-free
    // 5.7 s (scripts/bench/lossy_link.py has the current figures). Heartbeats only go
    // out while samples are unacknowledged, so a short period costs little when idle.
    p.heartbeat_period_s = 0.01;
    p.nack_response_delay_s = 0.0;
    p.heartbeat_response_delay_s = 0.0;
    // Repair first: a negative acknowledgement is answered whenever it comes.
    p.nack_suppression_s = 0.0;
    return p;
  }
  std::string valid;
  for (const auto& n : network_profile_names()) valid += (valid.empty() ? "" : ", ") + n;
  throw InputError("option --network: '" + name + "' is not a network profile (" + valid + ")");
}

}  // namespace tessera::transport
