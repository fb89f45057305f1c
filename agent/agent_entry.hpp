#pragma once
// The whole of tessera-agent behind one function, so that the standalone executable
// (agent_main.cpp) and `tessera launch`'s fork server (launch/fork_server/) run the very same
// code with the same argv.

namespace tessera::agent {

/// Runs one agent process: parses argv (argv[0] is the program name), opens the DDS session,
/// runs the agent and returns the process exit code (0 done, 2 bad input, 130 interrupted,
/// ...; transport/run_failure.hpp). The caller ends the process with transport::exit_process(),
/// which skips static destructors. Creates the process's first Fast DDS object, so in a
/// forked child it must run after the fork, never in the parent.
int agent_main(int argc, char** argv);

}  // namespace tessera::agent
