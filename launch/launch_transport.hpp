#pragma once
// Which DDS transports `tessera launch` gives its processes when --transport is not given.
// No Fast DDS here: `tessera` itself does not link it.

#include <cstdint>
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
/// Above kMaxSharedMemoryAgents agents "udp" instead of "shm": with 64 processes on one
/// loaded 2-core host (load 40-50), Fast DDS 2.9's shared-memory ports failed three runs out
/// of three in their first minute (an agent aborted on "Interprocess mutex timeout when
/// locking"), where UDP carried the same runs through their set-up.
std::string launch_transport(const transport::SessionOptions& session,
                             const LaunchLossOptions& loss, std::uint32_t num_agents = 1);

/// Above this many agents of one host launch's default transport is UDP, and its default lease
/// kLargeTeamLeaseS.
constexpr std::uint32_t kMaxSharedMemoryAgents = 32;
/// The lease launch gives a run of more than kMaxSharedMemoryAgents agents when --lease is not
/// given: such a team shares a few cores, so a process may not be scheduled for seconds, and
/// the 1 s lease then declared live processes lost (a false lease expiry ends the run).
constexpr double kLargeTeamLeaseS = 30.0;

/// The lease of a launched run: `lease_s` when --lease was given (`given`), or the team is
/// small; else kLargeTeamLeaseS.
double launch_lease_s(double lease_s, bool given, std::uint32_t num_agents);

}  // namespace tessera::launch
