#pragma once
// How the generator's poses are shared among robots: robot r owns the contiguous ids
// [r n / N, (r + 1) n / N), the convention of the multi-robot PGO literature.

#include <cstddef>
#include <vector>

namespace tessera {

/// First id of robot r (r in [0, N]; robot_begin(N, n, N) = n). Needs 1 <= N <= n.
std::size_t robot_begin(std::size_t r, std::size_t n, std::size_t num_robots);

/// The robot of every pose id 0..n-1.
std::vector<std::size_t> robot_of_poses(std::size_t n, std::size_t num_robots);

}  // namespace tessera
