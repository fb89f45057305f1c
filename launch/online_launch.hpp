#pragma once
// `tessera launch GRAPH --agents N --online`: an online run on this host (docs/online.md).
// Starts `tessera-agent --online` for each robot and `tessera-replay` playing GRAPH onto the
// graph stream, waits for them, and merges the agents' summaries (agent 0's carries the
// updates and the final answer). No coordinator: the online agents agree on the graph through
// their epoch reports, so there is no partition to assign and no result to gather.

#include <string>
#include <vector>

namespace tessera::launch {

/// Whether argv asks for an online launch (`--online`).
bool wants_online_launch(const std::vector<std::string>& argv);
/// `tessera launch ... --online`; returns the exit code.
int run_online_launch(const std::vector<std::string>& argv);

}  // namespace tessera::launch
