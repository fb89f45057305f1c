#include "agent/agent_gate.hpp"

#include <iostream>
#include <string>

#include "runtime/agent_log.hpp"
#include "transport/peer_gate.hpp"
#include "transport/run_failure.hpp"
#include "transport/run_identity.hpp"

namespace tessera::agent {

using namespace tessera::transport;

void pass_agent_gate(AgentSession& s, const AgentOptions& o, const std::function<void()>& on_poll,
                     bool joining) {
  PeerGateOptions gate;
  gate.timeout_s = o.net.timeout_s;
  gate.stall_after_s = o.handshake_stall_s;
  gate.max_reopens = o.handshake_retries;
  gate.force_one_reopen = o.handshake_force_once;
  gate.joining = joining;
  const PeerGateResult gated = pass_peer_gate(s, gate, on_poll);
  for (const std::string& event : gated.events)
    std::cerr << agent_tag(o.id) << ": " << event << "\n";
  expect_ready(gated.status, s.mailroom(), o.net.timeout_s,
               s.options().security_dir.empty()
                   ? "the coordinator"
                   : "the DDS Security handshakes with the other processes",
               // (secured: unauthenticated participants are not counted as seen, but listed)
               s.peers_ever_seen() == 0 && s.peer_views().empty()
                   ? "no process of run '" + o.net.session.run_id + "' seen on domain " +
                         std::to_string(s.domain()) + " (is the coordinator running?)"
                   : gated.missing);
}

}  // namespace tessera::agent
