#pragma once
// What a tessera-agent keeps on disk so that a restarted process with the same id can rejoin
// its run: the local problem it assembled after the hand-off (its measurements and initial
// poses cannot be asked for again: the other agents no longer hold them) and its round
// protocol snapshots of the last two checkpoint rounds (two, so the coordinator can pick a
// round every other agent has reached even if this agent died just after writing the
// newest). The file itself is core's atomic, checksummed checkpoint file.

#include <cstdint>
#include <string>
#include <tessera/distributed/protocol_snapshot.hpp>
#include <vector>

#include "runtime/round_loop.hpp"

namespace tessera::agent {

struct AgentCheckpoint {
  std::string run_id;
  AgentLocalData local;
  std::vector<ProtocolSnapshot> snapshots;  ///< Oldest first; rounds strictly increasing.
};

/// DIR/agent-<id>.ckpt (one run per folder; the run id is checked on load).
std::string checkpoint_path(const std::string& dir, std::uint32_t agent_id);

std::string encode_checkpoint(const std::string& run_id, const AgentLocalData& local,
                              const std::vector<ProtocolSnapshot>& snapshots);
/// Throws CheckpointError naming `what` (the file) when the payload is not a checkpoint.
AgentCheckpoint decode_checkpoint(const std::string& payload, const std::string& what);

/// Reads and validates the checkpoint at `path` (CheckpointError naming the file otherwise):
/// header and checksum, contents, and that it belongs to `run_id`, agent `agent_id` of
/// `num_agents`.
AgentCheckpoint load_checkpoint(const std::string& path, const std::string& run_id,
                                std::uint32_t agent_id, std::uint32_t num_agents);

}  // namespace tessera::agent
