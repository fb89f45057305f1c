#include "transport/run_identity.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <tessera/util/input_error.hpp>

namespace tessera::transport {

void validate_run_id(const std::string& run_id) {
  if (run_id.empty() || run_id.size() > 64)
    throw InputError("option --run-id: must be 1 to 64 characters, got '" + run_id + "'");
  for (char c : run_id) {
    bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '_' || c == '.' || c == '-';
    if (!ok)
      throw InputError("option --run-id: '" + run_id +
                       "' may only contain letters, digits, '_', '.' and '-'");
  }
}

int domain_for_run(const std::string& run_id) {
  std::uint32_t h = 2166136261u;
  for (unsigned char c : run_id) {
    h ^= c;
    h *= 16777619u;
  }
  return 1 + static_cast<int>(h % static_cast<std::uint32_t>(kMaxDomain));
}

namespace {
// An agent id as participant names write it: decimal digits only, below kCoordinatorId.
std::optional<std::uint32_t> parse_agent_id(const std::string& id) {
  if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
  errno = 0;
  const unsigned long v = std::strtoul(id.c_str(), nullptr, 10);
  if (errno != 0 || v >= kCoordinatorId) return std::nullopt;
  return static_cast<std::uint32_t>(v);
}
}  // namespace

std::string PeerIdentity::describe() const {
  return coordinator ? std::string("the coordinator") : "agent " + std::to_string(agent_id);
}

std::string participant_name(const PeerIdentity& who) {
  return "tessera:" + who.run_id +
         (who.coordinator ? std::string(":coordinator") : ":agent:" + std::to_string(who.agent_id));
}

std::optional<PeerIdentity> parse_participant_name(const std::string& name) {
  const std::string prefix = "tessera:";
  if (name.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  std::string rest = name.substr(prefix.size());
  PeerIdentity who;
  const std::string coord = ":coordinator";
  if (rest.size() > coord.size() &&
      rest.compare(rest.size() - coord.size(), coord.size(), coord) == 0) {
    who.run_id = rest.substr(0, rest.size() - coord.size());
    who.coordinator = true;
    return who;
  }
  auto pos = rest.rfind(":agent:");
  if (pos == std::string::npos) return std::nullopt;
  const auto id = parse_agent_id(rest.substr(pos + 7));
  if (!id) return std::nullopt;
  who.run_id = rest.substr(0, pos);
  who.agent_id = *id;
  return who;
}

std::string online_participant_name(const std::string& run_id, std::uint32_t agent) {
  return "tessera-online:" + run_id + ":" + std::to_string(agent);
}

std::optional<std::uint32_t> parse_online_participant_name(const std::string& name,
                                                           const std::string& run_id) {
  const std::string prefix = "tessera-online:" + run_id + ":";
  if (name.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  return parse_agent_id(name.substr(prefix.size()));
}

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof(buf) - 1) != 0) return "unknown";
  return buf;
}

}  // namespace tessera::transport
