#pragma once
// Pose blocks on the wire, for every exchange of lifted poses between neighbour blocks (the
// round protocol's AgentState and the robust solve's GncAgent, which use different layouts).

#include <Eigen/Core>
#include <cstdint>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/protocol/messages.hpp>
#include <vector>

namespace tessera {

/// The columns of block `sender`'s public poses for its k-th adjacent block, from X (the
/// sender's block, (d+1) columns per pose in `layout.poses[sender]` order).
PoseBlockMessage encode_public_poses(const BlockLayout& layout, int sender, std::size_t k, int d,
                                     const Eigen::MatrixXd& X, BlockKind kind, std::uint32_t round,
                                     std::uint32_t phase);

/// Copies the message's poses into `copy` (the receiver's neighbour block: (d+1) columns per pose
/// of `neighbours`, ascending). Throws std::runtime_error, naming `receiver`, on a shape that does
/// not match `copy` or a pose that is not a neighbour.
void decode_neighbour_poses(const PoseBlockMessage& message,
                            const std::vector<std::size_t>& neighbours, int d, int receiver,
                            Eigen::MatrixXd& copy);

}  // namespace tessera
