#include "coordinator/final_merge.hpp"

#include <algorithm>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/io/g2o_writer.hpp>
#include <tessera/io/tum_writer.hpp>

#include "transport/message_mapping.hpp"
#include "transport/run_failure.hpp"

namespace tessera::coordinator {

using namespace tessera::transport;

MergedEstimate merge_final_estimates(const std::vector<wire::FinalEstimate>& finals,
                                     std::uint32_t num_agents, std::uint32_t epoch,
                                     const std::vector<std::uint32_t>& owner,
                                     const RunStructure& structure) {
  const std::size_t n = structure.num_poses;
  MergedEstimate out;
  out.poses.resize(n);
  out.bytes.assign(num_agents, 0);
  out.peak_rss.assign(num_agents, 0);
  std::vector<bool> seen(n, false);
  for (const auto& f : finals) {
    if (f.sender() >= num_agents || f.epoch() < epoch) continue;
    out.bytes[f.sender()] = f.bytes_sent();
    out.peak_rss[f.sender()] = f.peak_rss_bytes();
    out.rounds = std::max(out.rounds, f.rounds());
    auto list = final_poses(f);
    for (auto& [id, pose] : list) {
      if (id >= n || owner[id] != f.sender())
        throw RunFailure(kExitRunFailed, "agent " + std::to_string(f.sender()) + " returned pose " +
                                             std::to_string(id) + " which it does not own");
      if (pose.dim() != structure.d)
        throw RunFailure(kExitRunFailed, "final pose of the wrong dimension");
      out.poses[id] = std::move(pose);
      seen[id] = true;
    }
  }
  for (std::size_t id = 0; id < n; ++id)
    if (!seen[id])
      throw RunFailure(kExitRunFailed, "pose " + std::to_string(id) + " is missing from agent " +
                                           std::to_string(owner[id]) + "'s final estimate");
  return out;
}

void write_merged_poses(const RunStructure& structure, const std::vector<Pose>& poses,
                        const std::string& run_id, const std::string& g2o_path,
                        const std::string& tum_path) {
  if (!g2o_path.empty()) {
    PoseGraph g;
    g.d = structure.d;
    g.num_poses = structure.num_poses;
    g.source = "tessera-coordinator run " + run_id;
    write_g2o(g, poses, g2o_path);
  }
  if (!tum_path.empty()) write_tum(poses, tum_path);
}

}  // namespace tessera::coordinator
