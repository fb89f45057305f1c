#pragma once
// A whole-graph file parsed once by tessera-fork-server before it forks the agents of a run,
// so that the N agents inherit the parsed graph (copy-on-write pages they only read) instead
// of each parsing the same file while the coordinator partitions it on both cores
// (docs/dds-runtime.md, "Start-up"). Only a cache: an agent whose --graph was not
// preloaded, or was not parsed, reads the file itself and reports its errors as before.

#include <string>
#include <tessera/graph/pose_graph.hpp>

namespace tessera::agent {

/// Parses `path` (a whole multi-robot g2o file; not a robot file) and keeps it for
/// preloaded_graph(), in place of any graph kept before. Keeps nothing when the file is a robot
/// file or cannot be read or parsed: never throws, the agent then meets the error itself, with the
/// file and line.
void preload_graph(const std::string& path) noexcept;

/// The graph preload_graph() parsed from exactly `path`, or nullptr.
const PoseGraph* preloaded_graph(const std::string& path);

}  // namespace tessera::agent
