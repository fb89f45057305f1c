#pragma once
// Pose blocks riding in a round status sample (wire RoundStatus block_header, block_pose_ids,
// block_data). In a relayed run every agent but the relay sends its status of a round to the
// relay alone; an agent that updated its block in that step also sends its new public poses
// to each neighbour, the relay among them. Packed into the status, the block for the relay
// costs no delivery of its own: one sem_post and one wake-up of the relay's Fast DDS receive
// thread less (docs/dds-runtime.md, "Riding blocks"). The blocks keep the status's
// sender and epoch; the relay routes them as if they had come on its block topic. Internal
// to transport/.

#include <tessera/protocol/messages.hpp>
#include <vector>

#include "tessera.h"

namespace tessera::transport {

/// Appends `block` (sent by the status's sender, in its epoch) to `status`.
void attach_block(wire::RoundStatus& status, const PoseBlockMessage& block);
/// Removes and returns the blocks riding in `status`, in the order they were attached.
/// Throws TransportError when the fields do not describe whole blocks.
std::vector<PoseBlockMessage> detach_blocks(wire::RoundStatus& status);

}  // namespace tessera::transport
