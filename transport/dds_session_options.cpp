// The public session options (<tessera/dds/session.hpp>) as command-line options.

#include <tessera/dds/session.hpp>

#include "io/number_text.hpp"

namespace tessera::dds {

std::vector<std::string> SessionOptions::argv(bool with_timeout) const {
  const SessionOptions defaults;
  std::vector<std::string> out = {"--run-id", run_id};
  if (domain >= 0) out.insert(out.end(), {"--domain", std::to_string(domain)});
  if (lease_s != defaults.lease_s) out.insert(out.end(), {"--lease", exact_text(lease_s)});
  if (!peers.empty()) {
    std::string list;
    for (const auto& ip : peers) list += (list.empty() ? "" : ",") + ip;
    out.insert(out.end(), {"--peers", list});
  }
  if (network != defaults.network) out.insert(out.end(), {"--network", network});
  if (transport != defaults.transport) out.insert(out.end(), {"--transport", transport});
  if (!security_dir.empty()) out.insert(out.end(), {"--security", security_dir});
  if (with_timeout && timeout_s != defaults.timeout_s)
    out.insert(out.end(), {"--timeout", exact_text(timeout_s)});
  return out;
}

}  // namespace tessera::dds
