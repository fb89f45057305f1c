#pragma once
// The "sequential" baseline of a multi-robot file: each robot keeps its own poses (what
// distributed PGO systems do when every robot optimises the trajectory it recorded).

#include <optional>
#include <tessera/graph/pose_keys.hpp>
#include <vector>

namespace tessera {

/// Block of every one of the n poses = its robot (keys), when the keys name exactly `parts`
/// robots (more than one); nothing otherwise (the caller then splits ids into ranges).
std::optional<std::vector<int>> robot_partition(const PoseKeys& keys, std::size_t n, int parts);

}  // namespace tessera
