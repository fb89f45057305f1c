#include "transport/session_options.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <tessera/util/input_error.hpp>

#include "transport/network_profile.hpp"
#include "transport/run_identity.hpp"
#include "transport/security.hpp"

namespace tessera::transport {

std::vector<std::string> transport_names() {
  return {"default", "shm", "udp"};
}

void SessionOptions::validate() const {
  validate_run_id(run_id);
  if (domain > kMaxDomain)
    throw InputError("option --domain: " + std::to_string(domain) +
                     " is above the highest usable domain " + std::to_string(kMaxDomain));
  if (num_agents < 1 || num_agents > 1000)
    throw InputError("number of agents must be 1..1000, got " + std::to_string(num_agents));
  if (!coordinator && agent_id >= num_agents)
    throw InputError("option --id: " + std::to_string(agent_id) +
                     " is not below the number of agents " + std::to_string(num_agents));
  if (!(lease_s >= 0.2 && lease_s <= 60))
    throw InputError("option --lease: " + std::to_string(lease_s) + " s is outside 0.2..60 s");
  network_profile(network);  // throws for an unknown name
  const std::vector<std::string> transports = transport_names();
  if (std::find(transports.begin(), transports.end(), transport) == transports.end())
    throw InputError("option --transport: '" + transport + "' is not one of default, shm, udp");
  if (transport == "shm" && !initial_peers.empty())
    throw InputError(
        "option --transport: shm reaches processes of this host only, but --peers names hosts "
        "to contact (use --transport default or udp)");
  // The role's own files are checked when the session starts (security_files).
  if (!security_dir.empty()) check_security_dir(security_dir);
  if (!(write_timeout_s > 0)) throw InputError("write timeout must be positive");
  for (const auto& ip : initial_peers) {
    in_addr addr{};
    if (inet_pton(AF_INET, ip.c_str(), &addr) != 1)
      throw InputError("option --peers: '" + ip + "' is not an IPv4 address");
  }
}

}  // namespace tessera::transport
