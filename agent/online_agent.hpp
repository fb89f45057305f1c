#pragma once
// `tessera-agent --online`: one robot's agent in an online run (docs/online.md). Reads the
// graph stream, agrees with the other agents at each epoch boundary on the batches that enter
// (runtime/online_agent_view.hpp), solves the grown graph with the round protocol over its
// own topics (transport/online_channel.hpp) until the gradient is back under the tolerance,
// idles (a blocking wait, nothing sent) while nothing is new, and certifies when the stream
// ends.

#include <string>
#include <vector>

namespace tessera::agent {

/// Whether argv asks for the online mode (`--online`).
bool wants_online(const std::vector<std::string>& argv);
/// Runs the online agent; returns the exit code (0 done, 1 run failed, 2 bad input).
int online_agent_main(const std::vector<std::string>& argv);

}  // namespace tessera::agent
