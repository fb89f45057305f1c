#include "transport/riding_blocks.hpp"

#include <string>

#include "transport/transport_error.hpp"

namespace tessera::transport {

namespace {
constexpr std::size_t kHeader = 6;  // round, phase, kind, rank, dim, poses
}  // namespace

void attach_block(wire::RoundStatus& status, const PoseBlockMessage& block) {
  auto& h = status.block_header();
  h.insert(h.end(), {block.round, block.phase, static_cast<std::uint32_t>(block.kind), block.rank,
                     block.dim, static_cast<std::uint32_t>(block.pose_ids.size())});
  auto& ids = status.block_pose_ids();
  ids.insert(ids.end(), block.pose_ids.begin(), block.pose_ids.end());
  auto& data = status.block_data();
  data.insert(data.end(), block.data.begin(), block.data.end());
}

std::vector<PoseBlockMessage> detach_blocks(wire::RoundStatus& status) {
  std::vector<PoseBlockMessage> out;
  const auto& h = status.block_header();
  const auto& ids = status.block_pose_ids();
  const auto& data = status.block_data();
  const auto bad = [&](const std::string& why) {
    return TransportError("round status from agent " + std::to_string(status.sender()) +
                          " carries malformed pose blocks: " + why);
  };
  if (h.size() % kHeader != 0) throw bad("header of " + std::to_string(h.size()) + " values");
  std::size_t id_at = 0, data_at = 0;
  for (std::size_t at = 0; at < h.size(); at += kHeader) {
    PoseBlockMessage b;
    b.round = h[at];
    b.sender = status.sender();
    b.phase = h[at + 1];
    if (h[at + 2] > 2) throw bad("kind " + std::to_string(h[at + 2]) + " is not Y, P or V");
    b.kind = static_cast<BlockKind>(h[at + 2]);
    b.rank = h[at + 3];
    b.dim = h[at + 4];
    const std::size_t poses = h[at + 5];
    const std::size_t values = poses * b.rank * (b.dim + 1);
    if (ids.size() - id_at < poses || data.size() - data_at < values)
      throw bad("block " + std::to_string(at / kHeader) + " runs past the end");
    b.pose_ids.assign(ids.begin() + static_cast<std::ptrdiff_t>(id_at),
                      ids.begin() + static_cast<std::ptrdiff_t>(id_at + poses));
    b.data.assign(data.begin() + static_cast<std::ptrdiff_t>(data_at),
                  data.begin() + static_cast<std::ptrdiff_t>(data_at + values));
    id_at += poses;
    data_at += values;
    out.push_back(std::move(b));
  }
  if (id_at != ids.size() || data_at != data.size()) throw bad("values left over");
  status.block_header().clear();
  status.block_pose_ids().clear();
  status.block_data().clear();
  return out;
}

}  // namespace tessera::transport
