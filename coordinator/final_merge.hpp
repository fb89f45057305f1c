#pragma once
// Step 4 of a run on the coordinator's side: the agents' final estimates merged into one
// estimate of the whole graph, checked so that a wrong owner or a missing pose is an error
// instead of a silently incomplete result.

#include <cstdint>
#include <string>
#include <tessera/graph/pose.hpp>
#include <vector>

#include "coordinator/run_structure.hpp"
#include "tessera.h"

namespace tessera::coordinator {

struct MergedEstimate {
  std::vector<Pose> poses;              ///< Every pose of the graph, by id.
  std::vector<std::uint64_t> bytes;     ///< Bytes each agent sent, by agent id.
  std::vector<std::uint64_t> peak_rss;  ///< Each agent's peak resident set, bytes, by id.
  std::uint32_t rounds = 0;             ///< The most rounds any agent ran.
};

/// Merges the final estimates of epoch >= `epoch` (older ones are from before a
/// re-partition) of agents 0..num_agents-1; `owner` is the agent of every pose as now
/// assigned. Throws RunFailure when an agent returns a pose it does not own or of the wrong
/// dimension, or when a pose is missing.
MergedEstimate merge_final_estimates(const std::vector<wire::FinalEstimate>& finals,
                                     std::uint32_t num_agents, std::uint32_t epoch,
                                     const std::vector<std::uint32_t>& owner,
                                     const RunStructure& structure);

/// Writes the merged poses as g2o VERTEX lines to `g2o_path` and in the TUM format to
/// `tum_path` (each skipped when empty); `run_id` labels the g2o file.
void write_merged_poses(const RunStructure& structure, const std::vector<Pose>& poses,
                        const std::string& run_id, const std::string& g2o_path,
                        const std::string& tum_path);

}  // namespace tessera::coordinator
