#pragma once
// Initial poses for a distributed solve.
//   chordal      the centralized chordal initialization (the reference for comparisons).
//   distributed  no central solve: each robot (a contiguous id range [r n / R, (r + 1) n / R),
//                the generator's robots, see generate/robot_ranges.hpp) runs chordal
//                initialization on its own measurements, in its own frame; robots' frames are
//                then aligned through inter-robot measurements along a breadth-first spanning
//                tree over robots, rooted at the robot of pose 0; the aligned poses go to their
//                block owners. A robot whose own measurements are disconnected is treated as
//                one robot per component ("unit").
//
// The distributed initialization is split into the two steps a robot can do with only part of
// the data (robot_units: what one robot computes alone; align_units: what needs the units'
// poses at the ends of inter-robot measurements), so the DDS agents (agent/initialization_stage)
// run the very same arithmetic as distributed_initialization() and get bit-identical poses.

#include <cstddef>
#include <map>
#include <string>
#include <tessera/graph/pose.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera {

/// kFile: the input's VERTEX poses (graph.initial).
enum class DistributedInit { kChordal, kDistributed, kFile };

/// "chordal", "distributed", "file".
const char* init_name(DistributedInit init);
/// Throws InputError listing the valid names.
DistributedInit parse_init(const std::string& name);

/// One robot's trajectory pieces: the connected components ("units") of its measurements
/// with both endpoints in its poses, each initialised by chordal initialization in its own
/// frame (the unit's smallest pose at the identity).
struct RobotUnits {
  /// Global pose ids of each unit, ascending; units ordered by their smallest id.
  std::vector<std::vector<std::size_t>> members;
  /// Same shape: each member's pose in its unit's own frame.
  std::vector<std::vector<Pose>> poses;
};

/// The units of the robot owning poses [begin, end) of a d-dimensional graph. `measurements`
/// in file order (only those with both endpoints in [begin, end) are used; the others are
/// ignored). `source` names the input in error messages.
RobotUnits robot_units(int d, std::size_t begin, std::size_t end,
                       const std::vector<Measurement>& measurements, const std::string& source);

/// Where a pose at the end of an inter-unit measurement sits: its unit (global numbering:
/// every robot's units in robot order) and its pose in that unit's frame.
struct UnitPose {
  std::size_t unit = 0;
  Pose local;
};

/// Frames of units 0..num_units-1: breadth-first over units in index order (a new tree per
/// connected component, its first unit at the identity), each newly reached unit aligned by
/// the first measurement of `crossing` (inter-unit measurements in file order) that reaches
/// it. `endpoint` must hold every endpoint of `crossing`.
std::vector<Pose> align_units(int d, std::size_t num_units,
                              const std::vector<Measurement>& crossing,
                              const std::map<std::size_t, UnitPose>& endpoint);

/// frame o local (the unit's pose in the common frame).
Pose place_in_frame(const Pose& frame, const Pose& local);

/// The distributed initialization with `robots` robots (1 <= robots <= num_poses).
std::vector<Pose> distributed_initialization(const PoseGraph& graph, int robots);

/// Dispatches on `init` (robots is used by kDistributed only).
std::vector<Pose> initial_poses(const PoseGraph& graph, DistributedInit init, int robots);

}  // namespace tessera
