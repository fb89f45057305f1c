// Host one agent of a distributed run over DDS inside your own program: a robot's process that
// joins run RUN_ID as agent ID of ROBOTS, with its share of GRAPH. The rest of the run (the
// coordinator and the other agents) may be other programs or the installed executables, on
// this host or others, e.g.:
//   tessera-coordinator --agents 2 --run-id demo --graph GRAPH.g2o --summary s.json &
//   tessera-agent --graph GRAPH.g2o --robots 2 --id 1 --run-id demo &
//   host_agent GRAPH.g2o 2 0 demo
//   host_agent GRAPH.g2o ROBOTS ID RUN_ID [DOMAIN]

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <tessera/dds/agent.hpp>
#include <tessera/util/input_error.hpp>

int main(int argc, char** argv) {
  if (argc < 5 || argc > 6) {
    std::fprintf(stderr, "usage: host_agent GRAPH.g2o ROBOTS ID RUN_ID [DOMAIN]\n");
    return 2;
  }
  tessera::dds::AgentOptions agent;
  agent.graph = argv[1];
  agent.robots = static_cast<std::uint32_t>(std::atoi(argv[2]));
  agent.id = static_cast<std::uint32_t>(std::atoi(argv[3]));
  agent.session.run_id = argv[4];
  if (argc == 6) agent.session.domain = std::atoi(argv[5]);
  try {
    const tessera::dds::AgentResult result = tessera::dds::run_agent(agent);
    std::printf("%s", result.full_report().c_str());
    return result.exit_code;
  } catch (const tessera::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
