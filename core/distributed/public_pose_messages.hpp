#pragma once
// A block's public poses of a matrix sent to each of some neighbour blocks, one addressed
// message each (AgentState::publish: the poses that neighbour holds copies of). The protocols
// (the rounds, the refinement, the certificate, the saddle escape) exchange their vectors with
// their neighbours this way.

#include <Eigen/Core>
#include <cstdint>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/protocol/messages.hpp>
#include <utility>
#include <vector>

namespace tessera {

inline void send_public_poses(const AgentState& state, const Eigen::MatrixXd& X, BlockKind kind,
                              const std::vector<int>& recipients, std::uint32_t round,
                              std::uint32_t phase, std::vector<OutgoingMessage>& out) {
  for (int a : recipients)
    out.push_back(
        addressed_to(static_cast<std::uint32_t>(a), state.publish(X, kind, a, round, phase)));
}

}  // namespace tessera
