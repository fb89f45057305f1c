#pragma once
// Which agents keep a copy of which agent's data, so that losing one agent loses no
// measurement: each agent's local problem (every measurement touching its poses, its initial
// poses) and, refreshed during the run, its lifted poses are replicated to `replicas` other
// agents. Every process computes the same plan from the assignment and the structure, so no
// message is needed to agree on it.
//
// Choice: the neighbour blocks sharing the most cut measurements with the agent first (they
// already hold its public poses and the cut measurements, so they are the cheapest holders and
// the natural heirs of its poses), ties by lower id; agents with fewer neighbours than
// `replicas` fill up with the next agents in cyclic id order.

#include <cstdint>
#include <utility>
#include <vector>

namespace tessera {

/// holders[a] = the agents that keep a replica of agent a (distinct, never a itself; at most
/// min(replicas, N - 1) of them, best first). `structure` = endpoints of every measurement,
/// `owner` = agent of every pose (0..num_agents-1). Throws InputError on an endpoint or owner
/// out of range.
std::vector<std::vector<std::uint32_t>> replica_holders(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    const std::vector<std::uint32_t>& owner, std::uint32_t num_agents, std::uint32_t replicas);

/// The agents whose replica `holder` keeps (inverse of replica_holders), ascending.
std::vector<std::uint32_t> replicas_kept_by(const std::vector<std::vector<std::uint32_t>>& holders,
                                            std::uint32_t holder);

}  // namespace tessera
