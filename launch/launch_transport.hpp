#pragma once
// Which DDS transports `tessera launch` gives its processes when --transport is not given.
// No Fast DDS here: `tessera` itself does not link it.

#include <string>

#include "launch/launch_loss_policy.hpp"
#include "transport/session_options.hpp"

namespace tessera::launch {

/// "shm" (shared memory only) when every process of the run talks to the others on this host
/// alone, else "default" (shared memory + UDPv4, Fast DDS's own choice). Shared memory only
/// spares each process its UDP sockets, their receive threads and the interface scans at
/// start-up (docs/dds-runtime.md, "Start-up"). "default" when `session` names
/// --peers (other hosts), the lossy profile (its settings are UDP's), DDS Security (not
/// checked over shared memory only), or `loss` continues after a lost agent (those runs talk
/// UDP only anyway: a process SIGKILLed inside a shared-memory port can lock it).
std::string launch_transport(const transport::SessionOptions& session,
                             const LaunchLossOptions& loss);

}  // namespace tessera::launch
