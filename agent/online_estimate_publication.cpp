#include "agent/online_estimate_publication.hpp"

#include <filesystem>
#include <tessera/graph/connectivity.hpp>
#include <tessera/io/tum_writer.hpp>
#include <tessera/problem/rounding.hpp>
#include <vector>

namespace tessera::agent {

bool publish_online_estimate(const runtime::OnlineAgentView& view,
                             transport::OnlineChannel& channel, std::uint32_t epoch,
                             std::uint32_t id, const std::string& tum_dir) {
  const GraphStream* stream = view.stream();
  if (!stream || count_components(stream->graph()) != 1) return false;  // no common frame yet
  const std::vector<Pose> poses = round_solution(stream->graph(), view.iterate());
  const int d = stream->graph().d;
  // This agent's robot, and the robots of lost agents whose blocks this agent adopted.
  std::vector<std::uint32_t> robots = {id};
  for (std::uint32_t r : view.lost())
    if (view.own_block() >= 0 && view.adopter(r) == view.own_block()) robots.push_back(r);
  bool any = false;
  for (std::uint32_t robot : robots) {
    std::vector<std::uint64_t> index;
    std::vector<double> data;
    std::vector<Pose> mine;
    for (std::size_t k = 0; k < poses.size(); ++k) {
      if (stream->robot_of_pose()[k] != robot) continue;
      index.push_back(stream->key_of_pose()[k].index);
      data.insert(data.end(), poses[k].R.data(), poses[k].R.data() + d * d);
      data.insert(data.end(), poses[k].t.data(), poses[k].t.data() + d);
      mine.push_back(poses[k]);
    }
    if (mine.empty()) continue;
    channel.publish_estimate(epoch, d, index, data, robot);
    if (!tum_dir.empty()) {
      // Replaced whole: a reader never sees half a snapshot.
      const std::string path = tum_dir + "/robot" + std::to_string(robot) + ".tum";
      write_tum(mine, path + ".part");
      std::filesystem::rename(path + ".part", path);
    }
    any = true;
  }
  return any;
}

}  // namespace tessera::agent
