#include "session_args.hpp"

#include <tessera/util/input_error.hpp>

#include "io/number_text.hpp"
#include "transport/run_identity.hpp"

namespace tessera::cli {

std::set<std::string> session_option_names(SessionArgsFor who) {
  std::set<std::string> names = {"run-id",  "domain",    "lease",   "peers",
                                 "network", "transport", "security"};
  if (who == SessionArgsFor::kProcess) names.insert("timeout");
  return names;
}

std::set<std::string> with_session_options(std::set<std::string> names, SessionArgsFor who) {
  for (const auto& n : session_option_names(who)) names.insert(n);
  return names;
}

SessionArgs parse_session_args(const Arguments& args, SessionArgsFor who) {
  SessionArgs a;
  transport::SessionOptions& o = a.session;
  o.run_id = args.get_or("run-id", o.run_id);
  transport::validate_run_id(o.run_id);
  const long domain = args.get_long("domain", -1);
  if (args.has("domain") && (domain < 0 || domain > transport::kMaxDomain))
    throw InputError("option --domain: must be 0.." + std::to_string(transport::kMaxDomain));
  o.domain = static_cast<int>(domain);
  o.lease_s = args.get_double("lease", o.lease_s);
  o.initial_peers = args.get_list("peers");
  o.network = args.get_or("network", o.network);
  o.transport = args.get_or("transport", o.transport);
  o.security_dir = args.get_or("security", o.security_dir);
  if (args.has("security") && o.security_dir.empty())
    throw InputError("option --security: needs a folder (scripts/security/make_identities.sh)");
  if (who == SessionArgsFor::kProcess) {
    a.timeout_s = args.get_double("timeout", a.timeout_s);
    if (!(a.timeout_s > 0)) throw InputError("option --timeout: must be positive");
  }
  // Role fields are still defaults (agent 0 of 1), which validate() accepts; it checks the
  // lease range and the peer addresses here, before any participant exists.
  o.validate();
  return a;
}

std::vector<std::string> session_argv(const transport::SessionOptions& o) {
  const transport::SessionOptions defaults;
  std::vector<std::string> out = {"--run-id", o.run_id};
  if (o.domain >= 0) out.insert(out.end(), {"--domain", std::to_string(o.domain)});
  if (o.lease_s != defaults.lease_s) out.insert(out.end(), {"--lease", exact_text(o.lease_s)});
  if (!o.initial_peers.empty()) {
    std::string list;
    for (const auto& ip : o.initial_peers) list += (list.empty() ? "" : ",") + ip;
    out.insert(out.end(), {"--peers", list});
  }
  if (o.network != defaults.network) out.insert(out.end(), {"--network", o.network});
  if (o.transport != defaults.transport) out.insert(out.end(), {"--transport", o.transport});
  if (!o.security_dir.empty()) out.insert(out.end(), {"--security", o.security_dir});
  return out;
}

std::string session_options_help(SessionArgsFor who) {
  // clang-format off
  std::string h;
  if (who == SessionArgsFor::kProcess)
    h += "  --run-id ID        run id shared by all processes of the run (default \"default\");\n"
         "                     [A-Za-z0-9_.-], at most 64 characters\n";
  else
    h += "  --run-id ID        run id of every process (default: a fresh one per launch)\n";
  h += "  --domain D         DDS domain id 0..232 (default: derived from the run id)\n";
  if (who == SessionArgsFor::kProcess)
    h += "  --timeout S        bound on each wait for peers during set-up, in seconds (default 30)\n";
  h += "  --lease S          participant/liveliness lease in seconds: a dead peer is noticed after\n"
       "                     about this long (default 2, range 0.2..60)\n";
  if (who == SessionArgsFor::kLaunch)
    h += "                     (launch, more than 32 agents: default 30; a loaded host may not\n"
         "                     schedule a process for seconds)\n";
  h +=
       "  --peers IP[,IP]    IPv4 addresses to contact by unicast (when multicast is not available)\n"
       "  --network NAME     transport profile: default, or lossy for links that drop packets\n"
       "                     (1400-byte datagrams, 4 MB socket buffers, 10 ms heartbeat)\n";
  if (who == SessionArgsFor::kProcess)
    h += "  --transport T      DDS transports: default (shared memory + UDPv4), shm (shared\n"
         "                     memory only: every process on this host; not with --peers) or udp\n"
         "                     (UDPv4 only); runs that survive killed processes use UDP only\n";
  else
    h += "  --transport T      DDS transports of every process: default (shared memory + UDPv4),\n"
         "                     shm (shared memory only) or udp (UDPv4 only). Default here: shm,\n"
         "                     unless --peers, --network lossy, --security or --on-agent-loss\n"
         "                     continue (then default); udp above 32 agents (Fast DDS's shared-\n"
         "                     memory port locks time out with that many on a loaded host)\n";
  h +=
       "  --security DIR     DDS Security: authentication, access control and encryption with\n"
       "                     the CA, the signed governance and this process's identity in DIR\n"
       "                     (DIR/coordinator, DIR/agent_<k>; scripts/security/make_identities.sh)\n";
  // clang-format on
  return h;
}

}  // namespace tessera::cli
