#pragma once
// The agent's phase log (--verbose): one line per phase on stderr, prefixed with the agent's
// tag so the lines of N agents sharing a terminal (tessera launch) can be told apart.

#include <cstdint>
#include <iostream>
#include <string>

namespace tessera::agent {

/// "tessera-agent[I]": the prefix of every line an agent prints.
inline std::string agent_tag(std::uint32_t id) {
  return "tessera-agent[" + std::to_string(id) + "]";
}

struct AgentLog {
  std::string tag;  ///< agent_tag(id).
  bool verbose = false;
  void operator()(const std::string& what) const {
    if (verbose) std::cerr << tag << ": " << what << "\n";
  }
};

}  // namespace tessera::agent
