#pragma once
// N round protocols of one run over a graph cut into contiguous blocks, built as the in-process
// engine builds them (layout, lifted start, momentum scheme, one AgentState each), for the
// tests that drive core's protocol by hand.

#include <memory>
#include <tessera/distributed/agent_factory.hpp>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/round_protocol.hpp>
#include <tessera/graph/pose_graph.hpp>
#include <vector>

namespace tessera::test {

struct AgentsOfRun {
  /// Agent b owns poses [b n / N, (b + 1) n / N). `g` must outlive this object, which must not
  /// move (the agents hold references into it).
  AgentsOfRun(const PoseGraph& g, int N, const DistributedOptions& opt);
  AgentsOfRun(const AgentsOfRun&) = delete;
  AgentsOfRun& operator=(const AgentsOfRun&) = delete;

  const PoseGraph& graph;
  BlockLayout layout;
  std::unique_ptr<MomentumScheme> scheme;
  std::vector<std::unique_ptr<AgentState>> states;
  std::vector<std::unique_ptr<RoundProtocol>> protocols;
  std::vector<RoundProtocol*> agents;  ///< protocols, as the driver takes them
};

}  // namespace tessera::test
