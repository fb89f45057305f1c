#pragma once
// One epoch of an online agent (agent/online_agent.cpp), in named steps: the members report
// what they hold, every agent reads the members' reports (their block poses, their held
// batches, their convergence votes), enters what all of them hold, and then either ends the
// stream with the final solve, certifies the growing graph, idles, or solves the grown graph.

#include "agent/online_agent_state.hpp"
#include "agent/online_link.hpp"

namespace tessera::agent {

/// Runs epoch `state.epoch` and moves to the next. Returns false once the run is over (the
/// epoch after the final solve, whose reports carry every block's last poses). Throws
/// TakeoverNeeded out of any wait when a member was lost (--on-agent-loss continue).
bool epoch_step(OnlineAgentState& state, OnlineLink& link);

}  // namespace tessera::agent
