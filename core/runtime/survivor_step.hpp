#pragma once
// The coordinator's re-partition after agents are lost for good (the loss side of the
// arbiter's decision, see rejoin_arbiter.hpp kGiveUp): core's survivor re-partition on the
// structure the coordinator already has, as agent ids ready for the wire.

#include <cstdint>
#include <tessera/partition/graph_structure.hpp>
#include <vector>

namespace tessera::coordinator {

struct SurvivorAssignment {
  std::uint32_t epoch = 0;
  std::vector<std::uint32_t> owner;      ///< Surviving agent of every pose.
  std::vector<std::uint32_t> survivors;  ///< Ascending.
  std::vector<std::uint32_t> lost;       ///< Ascending.
  std::size_t moved_poses = 0;
  std::size_t cut_edges = 0;  ///< Measurements between survivors' blocks afterwards.
  double ms = 0;
};

/// New owners for the survivors when `lost` agents (of `num_agents`) are gone; `owner` is the
/// assignment before. Throws InputError when no agent would survive.
SurvivorAssignment reassign_for_survivors(const GraphStructure& graph,
                                          const std::vector<std::uint32_t>& owner,
                                          std::uint32_t num_agents,
                                          const std::vector<std::uint32_t>& lost,
                                          std::uint32_t epoch);

}  // namespace tessera::coordinator
