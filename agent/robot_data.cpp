#include "agent/robot_data.hpp"

#include <tessera/io/g2o_reader.hpp>

#include "runtime/preloaded_graph.hpp"
#include "runtime/robot_file.hpp"
#include "transport/run_failure.hpp"

namespace tessera::agent {

using namespace tessera::transport;

RobotShare load_robot_share(const std::string& path, std::uint32_t id, std::uint32_t robots) {
  // Parsed by the fork server before it forked this agent (launch): the same graph, read once.
  if (const PoseGraph* preloaded = preloaded_graph(path))
    return robot_share(*preloaded, id, robots);
  if (is_robot_file(path)) return read_robot_file(path, id);  // n comes with the assignment
  PoseGraph graph = read_g2o(path);
  return robot_share(graph, id, robots);
}

void check_assignment(RobotShare& share, const wire::PartitionAssignment& asg, std::uint32_t robots,
                      const std::string& path) {
  if (share.num_poses == 0) adopt_num_poses(share, asg.num_poses(), path);
  auto mismatch = [&](const std::string& what) {
    throw RunFailure(kExitBadInput,
                     "the coordinator's assignment does not fit this agent: " + what);
  };
  if (asg.num_agents() != robots)
    mismatch("it is for " + std::to_string(asg.num_agents()) +
             " agents, this agent was started with --robots " + std::to_string(robots));
  if (asg.num_poses() != share.num_poses || asg.owner().size() != share.num_poses)
    mismatch("it has " + std::to_string(asg.owner().size()) + " poses, " + path + " has " +
             std::to_string(share.num_poses));
  if (asg.dim() != static_cast<std::uint32_t>(share.d))
    mismatch("dimension " + std::to_string(asg.dim()) + " vs " + std::to_string(share.d));
  for (std::uint32_t o : asg.owner())
    if (o >= robots) mismatch("owner " + std::to_string(o) + " is not an agent id");
}

}  // namespace tessera::agent
