#pragma once
// What a Tessera participant tells every peer at discovery besides its name (run, role, id):
// a few key=value tags carried in the participant's USER_DATA QoS. They are read before any
// endpoint matches (also before DDS Security authentication), so they can steer decisions a
// process must take before it announces itself:
// - `udp_only`: this process talks UDP only; the coordinator sets it when the run survives a
//   killed agent (--replicas / --rejoin-timeout), and agents that see it on the coordinator
//   move to UDP only too (a process SIGKILLed inside a peer's shared-memory port leaves the
//   port locked; see transport/qos.hpp).
// - `replaces`: the GUID prefixes of every earlier participant of the same process, which this
//   one replaces (participants re-created before the process announced anything, e.g. after
//   a stalled DDS Security handshake). Peers forget them without treating them as lost. All
//   of them, not only the last: a peer may never have seen a short-lived one in between.
// - `retiring`: this participant is about to be deleted and replaced by a new one of the same
//   process; peers forget it at once, so its leaving is neither a loss nor a reason to stop.
//   Set on the live participant (a QoS change peers see within one announcement period)
//   shortly before it is deleted: the two never coexist, because a process's two participants
//   would match each other's endpoints and Fast DDS 2.9 with DDS Security sometimes keeps such
//   a match after the old one is gone (the new writer then waits for acknowledgements forever).
// Plain text "tessera-tags;udp_only=1;retiring=1;replaces=P1,P2", no Fast DDS types.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tessera::transport {

struct ParticipantTags {
  bool udp_only = false;  ///< This process uses no shared memory.
  bool retiring = false;  ///< About to be deleted and replaced (see above).
  /// GUID prefix texts (peer_tracking.hpp prefix_text()) of the participants replaced,
  /// oldest first; empty: a first participant. At most kMaxReplaced are encoded.
  std::vector<std::string> replaces;
  static constexpr std::size_t kMaxReplaced = 8;

  /// The USER_DATA bytes ("tessera-tags;udp_only=1;retiring=1;replaces=P1,P2"); empty when
  /// nothing is set, so
  /// a plain participant carries no user data at all.
  std::vector<std::uint8_t> encode() const;
  /// Inverse of encode(). Bytes that are not Tessera tags (other software's user data, garbage,
  /// unknown keys) give default tags: unknown keys are ignored so newer peers can add keys.
  static ParticipantTags decode(const std::vector<std::uint8_t>& bytes);
};

}  // namespace tessera::transport
