#pragma once
// launch(): one distributed solve on this host as separate processes, the coordinator and N
// agents talking over DDS (tessera-coordinator and tessera-agent, found next to the running
// executable, started through tessera-fork-server when it is there). `tessera launch` is
// parse_launch_options() + launch().

#include <string>
#include <tessera/dds/launch.hpp>

#include "launch/launch_options.hpp"

namespace tessera::launch {

/// The outcome of a run (public: <tessera/dds/launch.hpp>).
using LaunchResult = dds::LaunchResult;

/// Validates `options` (InputError naming the bad field), starts every process, streams the
/// coordinator's progress and the summary to stdout, and takes everything down on the first
/// failure, on the time limit and on SIGINT / SIGTERM. Throws InputError for bad input (missing
/// executables or graph files), std::runtime_error when the processes cannot be started.
LaunchResult launch(LaunchOptions options);

/// The folder of the running program (where `tessera launch` finds the executables).
std::string running_program_dir();

}  // namespace tessera::launch
