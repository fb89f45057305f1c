#pragma once
// When an agent re-creates its participant because a DDS Security handshake stalled (the peer
// gate, transport/peer_gate.hpp, decides it; Session::replace_participant does it).
//
// Why: Fast DDS 2.9 sometimes never completes one pair's PKI-DH handshake (one side's handshake
// writer never sends to that peer; docs/dds-runtime.md, "secured set-up stall"), and nothing in
// its API restarts a handshake; a new participant starts a new one. Exactly one side of a
// stalled pair re-creates, so the two never replace each other's fresh participant in turn:
// the agent when the peer is the coordinator (which never re-creates), the larger id when both
// are agents, and always the agent that joins a run in progress (a restarted agent asking to
// rejoin): its peers passed their gates long ago and never re-create, so a stall with a running
// agent of larger id was never cured (the rejoin waited until the coordinator gave up after
// --rejoin-timeout, seen once in CI and once in 133 loops of DdsRejoin.Secured*).

#include <cstdint>

#include "transport/run_identity.hpp"

namespace tessera::transport {

/// Whether agent `self_agent` re-creates its participant for its handshake with `peer`, a
/// participant discovered `known_for_s` seconds ago and not authenticated yet: it is this
/// agent's side of the pair to cure (`joining`: every side is, see above), and the handshake
/// is older than `stall_after_s`.
bool cures_stalled_handshake(std::uint32_t self_agent, const PeerIdentity& peer, double known_for_s,
                             double stall_after_s, bool joining = false);

}  // namespace tessera::transport
