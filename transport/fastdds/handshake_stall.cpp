#include "transport/fastdds/handshake_stall.hpp"

namespace tessera::transport {

bool cures_stalled_handshake(std::uint32_t self_agent, const PeerIdentity& peer, double known_for_s,
                             double stall_after_s, bool joining) {
  const bool ours = joining || peer.coordinator || self_agent > peer.agent_id;
  return ours && known_for_s >= stall_after_s;
}

}  // namespace tessera::transport
