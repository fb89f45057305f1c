#include <tessera/partition/robot_partition.hpp>

namespace tessera {

std::optional<std::vector<int>> robot_partition(const PoseKeys& keys, std::size_t n, int parts) {
  if (parts < 2 || keys.num_robots() != static_cast<std::size_t>(parts) || keys.robot.size() != n)
    return std::nullopt;
  return std::vector<int>(keys.robot.begin(), keys.robot.end());
}

}  // namespace tessera
