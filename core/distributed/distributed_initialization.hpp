#pragma once
// Initial poses for a distributed solve.
//   chordal      the centralized chordal initialization (the reference for comparisons).
//   distributed  no central solve: each robot (a contiguous id range of the sequential split,
//                as in a multi-robot file) runs chordal initialization on its own measurements,
//                in its own frame; robots' frames are then aligned through inter-robot
//                measurements along a breadth-first spanning tree over robots, rooted at the
//                robot of pose 0; the aligned poses go to their block owners. A robot whose own
//                measurements are disconnected is treated as one robot per component.

#include <string>
#include <vector>

#include "graph/pose.hpp"
#include "graph/pose_graph.hpp"

namespace tessera {

/// kFile: the input's VERTEX poses (graph.initial), what the DDS runtime's agents start from.
enum class DistributedInit { kChordal, kDistributed, kFile };

/// "chordal", "distributed", "file".
const char* init_name(DistributedInit init);
/// Throws InputError listing the valid names.
DistributedInit parse_init(const std::string& name);

/// The distributed initialization with `robots` robots (1 <= robots <= num_poses).
std::vector<Pose> distributed_initialization(const PoseGraph& graph, int robots);

/// Dispatches on `init` (robots is used by kDistributed only).
std::vector<Pose> initial_poses(const PoseGraph& graph, DistributedInit init, int robots);

}  // namespace tessera
