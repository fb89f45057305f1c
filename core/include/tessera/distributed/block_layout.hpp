#pragma once
// What every agent knows about the partition (global metadata, identical on all agents):
// which block owns each pose, each block's poses, which blocks are adjacent (joined by a cut
// measurement), which of its poses each block must publish to each neighbour, and a colouring
// of the block adjacency graph (blocks of one colour share no measurement, so they can be
// updated in the same round without interacting).

#include <cstddef>
#include <cstdint>
#include <tessera/graph/measurement.hpp>
#include <utility>
#include <vector>

namespace tessera {

struct BlockLayout {
  int num_blocks = 0;
  std::vector<int> owner;                       ///< Block of every pose.
  std::vector<std::vector<std::size_t>> poses;  ///< Each block's poses, ascending ids.
  std::vector<std::vector<int>> adjacent;       ///< Each block's neighbour blocks, ascending.
  /// public_to[b][k]: the poses of block b that block adjacent[b][k] needs (ascending ids).
  std::vector<std::vector<std::vector<std::size_t>>> public_to;
  std::vector<int> colour;                       ///< Colour of every block.
  std::vector<std::vector<int>> colour_classes;  ///< Blocks of each colour, ascending.

  /// Index of block `a` in adjacent[b], or -1.
  int adjacency_index(int b, int a) const;
};

/// Builds the layout of `assignment` (block id 0..N-1 per pose; every block non-empty).
/// The colouring is greedy in block-id order (smallest free colour), so it is deterministic.
/// Throws InputError when the assignment is malformed.
BlockLayout make_block_layout(std::size_t num_poses, const std::vector<Measurement>& measurements,
                              const std::vector<int>& assignment);

/// The same layout from the measurements' endpoints (i, j) alone: what an agent holds of the
/// whole graph (8 bytes a measurement instead of a Measurement's 72 without its values).
BlockLayout make_block_layout(std::size_t num_poses,
                              const std::vector<std::pair<std::uint32_t, std::uint32_t>>& endpoints,
                              const std::vector<int>& assignment);

}  // namespace tessera
