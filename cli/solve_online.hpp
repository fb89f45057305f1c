#pragma once
// `tessera solve GRAPH --online ...`: the online run in one process (core/online/): the graph
// is replayed as the robots' front ends would publish it and the agents solve while it grows.
// Called by run_solve when --online is given.

#include <chrono>
#include <string>

#include "arguments.hpp"

namespace tessera::cli {

/// Valued options and switches --online adds to `tessera solve`.
extern const char* const kOnlineValued[];
extern const char* const kOnlineSwitches[];
extern const char* kOnlineHelp;

int solve_online_command(const Arguments& args, const std::string& graph_path,
                         std::chrono::steady_clock::time_point start);

}  // namespace tessera::cli
