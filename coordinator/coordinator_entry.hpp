#pragma once
// The whole of tessera-coordinator behind one function, so that the standalone executable
// (coordinator_main.cpp) and `tessera launch`'s fork server (launch/fork_server/) run the very
// same code with the same argv.

namespace tessera::coordinator {

/// Runs the coordinator process: parses argv (argv[0] is the program name), opens the DDS
/// session, runs the coordinator and returns the process exit code (transport/run_failure.hpp).
/// The summary's timeline starts when this is called. The caller ends the process with
/// transport::exit_process(). Creates the process's first Fast DDS object, so in a forked child it
/// must run after the fork, never in the parent.
int coordinator_main(int argc, char** argv);

}  // namespace tessera::coordinator
