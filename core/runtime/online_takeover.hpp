#pragma once
// Where a lost agent's block goes in an online run (agent/online_agent.cpp). The survivors keep
// their own blocks and the lost block's poses are grown into the neighbouring survivor blocks
// (repartition_for_survivors, the batch runs' re-partition: only the lost poses move). The
// lost robot may still be publishing (its front end outlived its agent), so its new poses need
// an owner too: the survivor block that took most of its old poses adopts them, which keeps
// its odometry chain inside one block. Structure only, deterministic: every survivor computes
// the same plan from the same graph.

#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/partition/survivor_repartition.hpp>
#include <vector>

namespace tessera::runtime {

struct OnlineTakeoverPlan {
  std::vector<int> owner;  ///< New block of every pose (a lost robot's block is left empty).
  /// Lost robot -> the block that takes its future poses; -1 when it had no pose yet (its
  /// first poses then go to the smallest live block when they enter).
  std::map<std::uint32_t, int> adopter;
  std::size_t moved = 0;      ///< Poses that changed block (exactly the lost blocks' poses).
  std::size_t cut_after = 0;  ///< Measurements between blocks after the move.
};

/// `owner`: block of every pose of `graph`, block b being robot `robots[b]`'s; `lost`: robots
/// whose agents are lost (this time and before). Throws std::runtime_error when a lost block
/// has poses but no robot outside `lost` has a block to take them.
OnlineTakeoverPlan plan_online_takeover(const PoseGraph& graph, const std::vector<int>& owner,
                                        const std::vector<std::uint32_t>& robots,
                                        const std::set<std::uint32_t>& lost,
                                        const SurvivorRepartitionOptions& options = {});

}  // namespace tessera::runtime
