#include "distributed/pose_block_codec.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace tessera {

PoseBlockMessage encode_public_poses(const BlockLayout& layout, int sender, std::size_t k, int d,
                                     const Eigen::MatrixXd& X, BlockKind kind, std::uint32_t round,
                                     std::uint32_t phase) {
  const auto& ids = layout.public_to[static_cast<std::size_t>(sender)][k];
  const auto& own = layout.poses[static_cast<std::size_t>(sender)];
  const Eigen::Index w = (d + 1) * X.rows();
  PoseBlockMessage m;
  m.round = round;
  m.sender = static_cast<std::uint32_t>(sender);
  m.phase = phase;
  m.kind = kind;
  m.rank = static_cast<std::uint32_t>(X.rows());
  m.dim = static_cast<std::uint32_t>(d);
  m.pose_ids.reserve(ids.size());
  m.data.resize(ids.size() * static_cast<std::size_t>(w));
  double* out = m.data.data();
  for (std::size_t id : ids) {
    const auto slot = std::lower_bound(own.begin(), own.end(), id) - own.begin();
    m.pose_ids.push_back(static_cast<std::uint32_t>(id));
    std::memcpy(out, X.data() + w * slot, sizeof(double) * static_cast<std::size_t>(w));
    out += w;
  }
  return m;
}

void decode_neighbour_poses(const PoseBlockMessage& m, const std::vector<std::size_t>& nb, int d,
                            int receiver, Eigen::MatrixXd& copy) {
  const Eigen::Index w = (d + 1) * copy.rows();
  if (m.rank != static_cast<std::uint32_t>(copy.rows()) || m.dim != static_cast<std::uint32_t>(d) ||
      m.data.size() != m.pose_ids.size() * static_cast<std::size_t>(w))
    throw std::runtime_error("agent " + std::to_string(receiver) + ": pose message from agent " +
                             std::to_string(m.sender) + " has the wrong shape");
  const double* in = m.data.data();
  for (std::uint32_t id : m.pose_ids) {
    auto it = std::lower_bound(nb.begin(), nb.end(), static_cast<std::size_t>(id));
    if (it == nb.end() || *it != id)
      throw std::runtime_error("agent " + std::to_string(receiver) + ": pose " +
                               std::to_string(id) + " from agent " + std::to_string(m.sender) +
                               " is not a neighbour");
    std::memcpy(copy.data() + w * (it - nb.begin()), in,
                sizeof(double) * static_cast<std::size_t>(w));
    in += w;
  }
}

}  // namespace tessera
