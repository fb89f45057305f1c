#pragma once
// The command lines of a launch run's processes: the coordinator's and each agent's, as their
// standalone executables would get them, and the fork spec that starts them in order.

#include <string>
#include <vector>

#include "launch/fork_spec.hpp"
#include "launch/launch_options.hpp"

namespace tessera::launch {

/// Where a run's pieces are on this host.
struct RunPaths {
  std::string bin;      ///< folder holding tessera-coordinator and tessera-agent
  std::string work;     ///< the run's temporary folder (logs)
  std::string graph;    ///< the graph file, or the robot files' folder or list
  std::string summary;  ///< where the coordinator writes its JSON summary
};

/// The processes to start, in order: the coordinator (stdout = launch's progress pipe), then
/// agents 0..N-1; `names` and `agent_ids` label them in the same order.
struct ProcessPlan {
  ForkSpec spec;
  std::vector<std::string> names;
  std::vector<long> agent_ids;
};

/// The coordinator's argv (argv[0] its executable). `o.net.session` must hold the run id.
std::vector<std::string> coordinator_argv(const LaunchOptions& o, const RunPaths& paths);

/// Agent `k`'s argv (argv[0] its executable).
std::vector<std::string> agent_argv(const LaunchOptions& o, const RunPaths& paths, long k);

/// Every process of the run; `progress_fd` is the coordinator's stdout.
ProcessPlan plan_processes(const LaunchOptions& o, const RunPaths& paths, int progress_fd);

}  // namespace tessera::launch
