#include "launch/launch_transport.hpp"

namespace tessera::launch {

std::string launch_transport(const transport::SessionOptions& session,
                             const LaunchLossOptions& loss, std::uint32_t num_agents) {
  const bool this_host_only = session.initial_peers.empty() && session.network == "default" &&
                              session.security_dir.empty() && loss.action == AgentLossAction::kStop;
  if (!this_host_only) return "default";
  return num_agents > kMaxSharedMemoryAgents ? "udp" : "shm";
}

double launch_lease_s(double lease_s, bool given, std::uint32_t num_agents) {
  return given || num_agents <= kMaxSharedMemoryAgents ? lease_s : kLargeTeamLeaseS;
}

}  // namespace tessera::launch
