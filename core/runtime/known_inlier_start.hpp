#pragma once
// A robust run's second candidate start over DDS (GncDistributedOptions::known_inlier_start):
// the agents' distributed initialization of the known inliers alone, as the in-process
// engine's known_inlier_poses() computes it, when those measurements connect the poses; the
// agents then vote between it and the run's own initialization (robust/gnc_agent.hpp). Every
// agent decides the same from the structure (endpoints of every measurement, the known-inlier
// rule on them and the input's flags from the assignment).

#include <cstdint>
#include <optional>
#include <tessera/robust/robust_options.hpp>
#include <utility>
#include <vector>

#include "runtime/local_share.hpp"

namespace tessera::agent {

struct KnownInlierStart {
  RobotShare share;  ///< The robot's share without its measurements that may be rejected.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> structure;  ///< Known inliers only.
};

/// `share` and `structure` restricted to the known inliers (by `rule`, or flagged in `flags`:
/// empty or one per measurement of `structure`, the share's measurement_index being positions
/// in it), or nullopt when those leave the poses unconnected (the run's own initialization is
/// used then).
std::optional<KnownInlierStart> known_inlier_start(
    const RobotShare& share, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& structure,
    KnownInliers rule, const std::vector<bool>& flags = {});

}  // namespace tessera::agent
