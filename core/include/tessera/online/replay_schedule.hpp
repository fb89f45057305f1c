#pragma once
// `tessera replay`'s timeline: a multi-robot graph played as the robots' front ends would
// publish it. Robot r moves along its own poses (in id order) at `rate` poses per second
// from its start time; each tick publishes one batch with the new pose (its guess from the
// graph's initial values, if any) and every measurement that becomes observable then: a
// measurement is published once both of its poses exist, by the robot whose pose came last
// (an inter-robot closure when the later robot reaches it). Times are divided by `speedup`.

#include <cstddef>
#include <cstdint>
#include <string>
#include <tessera/graph/pose_graph.hpp>
#include <tessera/online/stream_batch.hpp>
#include <vector>

namespace tessera {

struct ReplayOptions {
  double rate = 10.0;    ///< Poses per second per robot, > 0.
  double speedup = 1.0;  ///< Time divisor, > 0 (10 = ten times faster than real time).
  /// Seconds (before the speedup) at which each robot starts moving, by robot; missing
  /// robots start at 0. >= 0 each. A robot that starts late joins the run late.
  std::vector<double> start_s;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

struct ReplayPlan {
  /// Every robot's batches, ordered by stamp (then robot): the publication order.
  std::vector<StreamBatch> batches;
  /// The graph id behind each stream key: pose k of robot r is graph id original_id[r][k].
  std::vector<std::vector<std::size_t>> original_id;
  std::size_t measurements = 0;  ///< Measurements published (all of the graph's).
  double duration_s = 0.0;       ///< Stamp of the last batch.
};

/// `robot_of_pose`: robot of every pose id (0..R-1, each robot with at least one pose),
/// e.g. robot_of_poses(n, R) for the contiguous ranges of `generate --split`. Throws
/// InputError (naming graph.source) when sizes do not fit or a robot has no pose.
ReplayPlan plan_replay(const PoseGraph& graph, const std::vector<std::size_t>& robot_of_pose,
                       const ReplayOptions& options);

}  // namespace tessera
