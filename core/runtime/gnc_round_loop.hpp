#pragma once
// The robust (GNC-TLS) variant of run_round_loop(): the agent runs core's GncAgent
// (robust/gnc_agent.hpp), the same state machine the in-process engine runs, over the
// channel, then rounds the kept set's solution like the plain loop. No checkpoints: a robust
// run cannot roll back (the coordinator refuses --robust with --rejoin-timeout or --replicas).

#include "runtime/round_loop.hpp"

namespace tessera::agent {

/// `local.options.robust` must be a robust kind. Returns the plain loop's result for the kept
/// set (its poses, cost over the kept measurements, certificate) with `robust` set; `rounds`
/// counts every solve.
RoundLoopResult run_gnc_round_loop(const AgentLocalData& local, ProtocolChannel& channel,
                                   double receive_timeout_s);

}  // namespace tessera::agent
