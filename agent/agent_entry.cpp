// tessera-agent's body: parses the options and wires the pieces: the run itself is
// agent_run.cpp (set-up steps in run_setup.cpp), the process life around the DDS session
// cli/session_process.hpp.

#include "agent/agent_entry.hpp"

#include <iostream>
#include <optional>
#include <string>
#include <tessera/distributed/checkpoint_file.hpp>
#include <vector>

#include "agent/agent_options.hpp"
#include "agent/agent_run.hpp"
#include "agent/online_agent.hpp"
#include "cli/session_process.hpp"
#include "launch/process_tuning.hpp"
#include "runtime/agent_log.hpp"
#include "transport/signal_watcher.hpp"

namespace tessera::agent {

int agent_main(int argc, char** argv) {
  // An online agent has no Session: default signal handling (SIGTERM ends it).
  if (wants_online(std::vector<std::string>(argv + 1, argv + argc)))
    return online_agent_main(std::vector<std::string>(argv + 1, argv + argc));
  transport::SignalWatcher
      signals;                    // first: every thread created later inherits the blocked signals
  launch::begin_agent_process();  // process-level tuning (launch/process_tuning.hpp)
  const std::vector<std::string> argv_list(argv + 1, argv + argc);
  AgentOptions options;
  if (auto code = cli::parse_process_options(
          argv_list, "tessera-agent", cli::process_help(kAgentUsage), parse_agent_options, options))
    return *code;
  const std::string tag = agent_tag(options.id);
  // A checkpoint of this run in --checkpoint-dir means this process is a restart: rejoin.
  std::optional<AgentCheckpoint> restart;
  try {
    restart = find_restart_checkpoint(options);
  } catch (const CheckpointError& e) {
    std::cerr << tag << ": error: " << e.what() << "\n";
    return transport::kExitBadInput;
  }
  const cli::ProcessRole role{tag, options.net.timeout_s, true, true};
  return cli::run_session_process(
      agent_session_options(options), role, signals,
      [&](transport::AgentSession& session) { run_agent(options, session, std::move(restart)); });
}

}  // namespace tessera::agent
