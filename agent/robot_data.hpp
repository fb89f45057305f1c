#pragma once
// This robot's data in a run: its share read from --graph (the whole multi-robot file or
// the robot's own file), and the check that the coordinator's assignment fits it, so that a
// process started with the wrong file or --robots fails naming the mismatch (exit 2) instead
// of running on inconsistent data.

#include <cstdint>
#include <string>

#include "runtime/local_share.hpp"
#include "tessera.h"

namespace tessera::agent {

/// Robot `id`'s share of `path` (of `robots` robots). A robot's own file does not say n:
/// its num_poses stays 0 until check_assignment. Throws InputError naming the file.
RobotShare load_robot_share(const std::string& path, std::uint32_t id, std::uint32_t robots);

/// Adopts the assignment's n when the share does not know it, then checks the assignment's
/// number of agents, poses, dimension and owners against `share`. Throws RunFailure (exit
/// code 2, "the coordinator's assignment does not fit this agent: ...") on a mismatch.
void check_assignment(RobotShare& share, const wire::PartitionAssignment& asg, std::uint32_t robots,
                      const std::string& path);

}  // namespace tessera::agent
