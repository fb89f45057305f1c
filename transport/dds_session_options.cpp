// The public session options (<tessera/dds/session.hpp>) as command-line options.

#include <cstdio>
#include <tessera/dds/session.hpp>

namespace tessera::dds {

namespace {

// Exactly the double (the processes parse it back).
std::string exact(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", x);
  return buf;
}

}  // namespace

std::vector<std::string> SessionOptions::argv(bool with_timeout) const {
  const SessionOptions defaults;
  std::vector<std::string> out = {"--run-id", run_id};
  if (domain >= 0) out.insert(out.end(), {"--domain", std::to_string(domain)});
  if (lease_s != defaults.lease_s) out.insert(out.end(), {"--lease", exact(lease_s)});
  if (!peers.empty()) {
    std::string list;
    for (const auto& ip : peers) list += (list.empty() ? "" : ",") + ip;
    out.insert(out.end(), {"--peers", list});
  }
  if (network != defaults.network) out.insert(out.end(), {"--network", network});
  if (transport != defaults.transport) out.insert(out.end(), {"--transport", transport});
  if (!security_dir.empty()) out.insert(out.end(), {"--security", security_dir});
  if (with_timeout && timeout_s != defaults.timeout_s)
    out.insert(out.end(), {"--timeout", exact(timeout_s)});
  return out;
}

}  // namespace tessera::dds
