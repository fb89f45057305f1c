#pragma once
// Text output of an agent: its local problem after the hand-off (for tests and debugging)
// and its final poses as g2o VERTEX lines.

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/round_loop.hpp"

namespace tessera::agent {

/// Writes `local` as text, one record per line, numbers in %.17g:
///   "AGENT id N d n"
///   "STRUCTURE m"                                  edges of the whole graph's structure
///   "OWNED id"                                     per owned pose
///   "POSE id R(col-major, d*d) t(d)"               per owned pose with an initial value
///   "MEAS index i j kappa tau R(col-major) t"      per local measurement
/// Throws InputError naming `path` when it cannot be written.
void write_local_dump(const AgentLocalData& local, const std::string& path);

/// Writes VERTEX_SE2 ("id x y theta") or VERTEX_SE3:QUAT ("id x y z qx qy qz qw") lines.
void write_vertices_g2o(const std::vector<std::uint32_t>& ids, const std::vector<Pose>& poses,
                        int d, const std::string& path);

}  // namespace tessera::agent
