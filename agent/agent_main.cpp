// tessera-agent: one robot's process in a distributed run. Thin over core/ (graph I/O,
// the round protocol) and transport/ (DDS). See docs/dds-runtime.md.
//
// main() only parses the options and wires the pieces: the run itself is agent_run.cpp
// (set-up steps in run_setup.cpp), the process life around the DDS session
// cli/session_process.hpp.

#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "agent/agent_log.hpp"
#include "agent/agent_options.hpp"
#include "agent/agent_run.hpp"
#include "distributed/checkpoint_file.hpp"
#include "session_process.hpp"
#include "transport/signal_watcher.hpp"

using namespace tessera;

int main(int argc, char** argv) {
  transport::SignalWatcher
      signals;  // first: every thread created later inherits the blocked signals
  const std::vector<std::string> argv_list(argv + 1, argv + argc);
  agent::AgentOptions options;
  if (auto code = cli::parse_process_options(argv_list, "tessera-agent",
                                             cli::process_help(agent::kAgentUsage),
                                             agent::parse_agent_options, options))
    return *code;
  const std::string tag = agent::agent_tag(options.id);
  // A checkpoint of this run in --checkpoint-dir means this process is a restart: rejoin.
  std::optional<agent::AgentCheckpoint> restart;
  try {
    restart = agent::find_restart_checkpoint(options);
  } catch (const CheckpointError& e) {
    std::cerr << tag << ": error: " << e.what() << "\n";
    return transport::kExitBadInput;
  }
  const cli::ProcessRole role{tag, options.net.timeout_s, true};
  cli::exit_process(cli::run_session_process(
      agent::agent_session_options(options), role, signals, [&](transport::Session& session) {
        agent::run_agent(options, session, std::move(restart));
      }));
}
