#pragma once
// The agents' distributed rounding (core/runtime/distributed_rounding.hpp) run in process: one
// thread per agent over an in-memory channel, no DDS. Used by distributed_rounding_test and by
// rounding_iterations_bench (scripts/bench/rounding_iterations.py).

#include <cstddef>
#include <cstdint>
#include <string>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

#include "runtime/distributed_rounding.hpp"

namespace tessera::agent {

/// A graph, its block assignment and the in-process solver's result on it (the iterate the
/// rounding starts from).
struct RoundingCase {
  PoseGraph graph;
  std::vector<int> assignment;
  DistributedResult solved;
};

struct Rounded {
  std::vector<Pose> poses;  ///< Global order.
  double cost = 0;          ///< As the agents summed it.
  std::uint32_t iterations = 0;
  /// The interface solve's team interface poses (0: the CG ran) and agent 0's message steps.
  std::uint32_t interface_poses = 0, steps = 0;
  /// Empty when every agent finished with the same cost and iteration count; else what failed.
  std::vector<std::string> errors;
};

/// A generated 3D grid of `poses` (generator seed `seed`) in `agents` blocks: contiguous runs of
/// pose ids, or with `partitioned` the `fast` partition's (compact pieces of the grid, as launch
/// splits large graphs); and the in-process solver's iterate after `max_rounds` rounds (a point
/// near, not at, a critical point, as the runs the rounding follows usually stop).
RoundingCase grid_rounding_case(std::size_t poses, int agents, int max_rounds, bool partitioned,
                                std::uint64_t seed);

/// Runs DistributedRounding with `options` on every block of `c` in its own thread; an agent
/// that waits longer than `timeout_s` for a message fails (Rounded::errors).
Rounded round_in_threads(const RoundingCase& c, const DistributedRoundingOptions& options,
                         double timeout_s = 30.0);

}  // namespace tessera::agent
