#pragma once
// One robot's own g2o file: the input of `tessera-agent --graph FILE` when FILE holds only
// that robot's data (written by `tessera generate --split DIR`; convention in
// docs/dds-runtime.md, "One file per robot"):
//   - ordinary VERTEX_* / EDGE_* lines with the GLOBAL pose ids of the multi-robot graph;
//   - VERTEX lines (optional, all or none) for the robot's own poses only;
//   - EDGE lines for the measurements the robot holds: each has at least one endpoint among
//     its poses; the other may be another robot's pose (an inter-robot loop closure,
//     "referenced but not owned");
//   - `# tessera-robot poses B E`: the robot owns the contiguous ids [B, E). Optional when
//     VERTEX lines are present (then [smallest, largest + 1] of their ids, which must be
//     contiguous);
//   - `# tessera-measurement-index K1 K2 ...` (optional): each EDGE line's position in the
//     whole graph, in line order, so the run orders measurements exactly as the single file
//     would; without it a measurement's position is (robot id << 40) + its line order;
//   - `# tessera-known-inliers K1 K2 ...` (optional): the positions of the measurements a
//     robust run must never down-weight (a dpgo CSV file's is_known_inlier column; `tessera
//     launch` on a CSV writes it). The agents announce them and the coordinator's assignment
//     gives every agent the whole set.
// The file does not say how many poses the whole graph has: n is the end of the last
// robot's range, learned from the announcements (the coordinator checks that the ranges
// tile 0..n-1 in agent order and sends n in the assignment).

#include <cstdint>
#include <string>

#include "runtime/local_share.hpp"

namespace tessera::agent {

/// True when the file at `path` has a `# tessera-robot` line (it holds one robot's data).
bool is_robot_file(const std::string& path);

/// Reads robot `robot`'s own file. The share's num_poses is 0 (unknown) until
/// adopt_num_poses(). Values are parsed by core's g2o reader (the same doubles as from the
/// whole file). Throws InputError naming the file and line for anything inconsistent.
RobotShare read_robot_file(const std::string& path, std::uint32_t robot);

/// Sets the whole graph's n (from the assignment); throws InputError (naming `source`) when
/// one of the share's measurements names a pose >= n or its range does not fit.
void adopt_num_poses(RobotShare& share, std::size_t n, const std::string& source);

}  // namespace tessera::agent
