#pragma once
// The peer gate (transport/peer_gate.hpp) as an agent runs it: with its --timeout,
// --handshake-stall and --handshake-retries, each participant re-creation logged, a timeout or
// stop turned into a RunFailure naming what was missing. Run by a fresh agent before it
// announces itself (run_setup.cpp) and, in a secured run, by a restarted agent before it asks
// to rejoin (agent_run.cpp): without it a stalled DDS Security handshake of the restarted
// process would only end in "timed out ... waiting to rejoin".

#include <functional>

#include "agent/agent_options.hpp"
#include "transport/agent_session.hpp"

namespace tessera::agent {

/// Returns once the gate passed. `on_poll` runs on every look at the peers (it may throw to
/// end the wait, e.g. refuse_if_lost). Throws RunFailure on a stop or a timeout.
/// `joining`: a restarted agent before its rejoin request (PeerGateOptions::joining).
void pass_agent_gate(transport::AgentSession& session, const AgentOptions& options,
                     const std::function<void()>& on_poll = {}, bool joining = false);

}  // namespace tessera::agent
