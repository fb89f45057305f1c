#pragma once
// What a session knows about one live peer of its run before any message was exchanged
// (Session::peer_views()): who it is, how long it has been known, whether the DDS Security
// handshake with it finished, and the tags its participant carries. No DDS types.

#include "transport/participant_tags.hpp"
#include "transport/run_identity.hpp"

namespace tessera::transport {

struct PeerView {
  PeerIdentity who;
  double known_for_s = 0;  ///< Seconds since discovery (or since this process's participant
                           ///< was last replaced, whichever is later).
  /// DDS Security handshake done both ways: Fast DDS reported it authorized and this process's
  /// control writer and reader matched the peer's (Session::peer_views). Always true when
  /// unsecured.
  bool authenticated = false;
  ParticipantTags tags;
};

}  // namespace tessera::transport
