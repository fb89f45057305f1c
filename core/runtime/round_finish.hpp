#pragma once
// What every agent does after its protocol, plain or robust: round the final lifted iterate to
// SE(d) with no central step (DistributedRounding), sum the certificate traffic, and, on agent
// 0, send the reports the coordinator's summary reads (agent_report.hpp).

#include <chrono>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>

#include "runtime/round_loop.hpp"
#include "runtime/round_mailbox.hpp"

namespace tessera::agent {

/// `local`: the agent's data as the rounding sees it (its measurements: those of the solved
/// problem); `layout`/`state`: the final solve's. `certified_sequence`: certification ran
/// (its traffic is summed over the agents). `solve_start`: when the protocol began (solve_s).
RoundLoopResult round_and_report(const AgentLocalData& local, const BlockLayout& layout,
                                 const AgentState& state, Mailbox& mail, ProtocolChannel& channel,
                                 RoundLoopResult res, bool certified_sequence,
                                 std::chrono::steady_clock::time_point solve_start);

}  // namespace tessera::agent
