#include "generate/robot_ranges.hpp"

namespace tessera {

std::size_t robot_begin(std::size_t r, std::size_t n, std::size_t num_robots) {
  return r * n / num_robots;
}

std::vector<std::size_t> robot_of_poses(std::size_t n, std::size_t num_robots) {
  std::vector<std::size_t> robot(n);
  for (std::size_t r = 0; r < num_robots; ++r)
    for (std::size_t k = robot_begin(r, n, num_robots); k < robot_begin(r + 1, n, num_robots); ++k)
      robot[k] = r;
  return robot;
}

}  // namespace tessera
