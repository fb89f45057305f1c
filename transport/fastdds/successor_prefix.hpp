#pragma once
// The GUID prefix of a re-created participant (Session::replace_participant).
//
// Why: Fast DDS 2.9 would derive the same prefix as before (host, process, lowest free
// participant number; with DDS Security a hash of that and the identity), and peers that still
// hold state of the deleted participant then mistake the new one for it (seen: its endpoints
// never match, "Cannot find remote writer"). Fast DDS offers no way to make a peer forget a
// participant at once, so the new participant takes a prefix no first participant has.

#include <cstddef>

#include "transport/peer_tracking.hpp"

namespace tessera::transport {

/// A prefix for the `generation`-th re-creation of the participant whose prefix was `old`.
/// Unsecured: same vendor, host and process bytes (Fast DDS's locality checks read them), a
/// participant number no first participant has. `secured`: the prefix is only a seed that
/// Fast DDS hashes, so any unused value does.
GuidPrefix successor_prefix(const GuidPrefix& old, bool secured, std::size_t generation);

}  // namespace tessera::transport
