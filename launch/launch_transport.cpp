#include "launch/launch_transport.hpp"

namespace tessera::launch {

std::string launch_transport(const transport::SessionOptions& session,
                             const LaunchLossOptions& loss) {
  const bool this_host_only = session.initial_peers.empty() && session.network == "default" &&
                              session.security_dir.empty() && loss.action == AgentLossAction::kStop;
  return this_host_only ? "shm" : "default";
}

}  // namespace tessera::launch
