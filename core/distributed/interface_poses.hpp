#pragma once
// A block's interface: its poses that some neighbour block needs (a cut measurement touches
// them), ascending ids. The certificate's interface test and the refinement's interface solves
// order and size their Schur complements by this same set.

#include <algorithm>
#include <cstddef>
#include <tessera/distributed/block_layout.hpp>
#include <vector>

namespace tessera {

inline std::vector<std::size_t> interface_poses(const BlockLayout& layout, int b) {
  std::vector<std::size_t> poses;
  for (const auto& to : layout.public_to[static_cast<std::size_t>(b)])
    poses.insert(poses.end(), to.begin(), to.end());
  std::sort(poses.begin(), poses.end());
  poses.erase(std::unique(poses.begin(), poses.end()), poses.end());
  return poses;
}

}  // namespace tessera
