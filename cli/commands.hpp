#pragma once
// The subcommands of `tessera`. Each lives in its own command_<name>.cpp and returns the
// process exit code; InputError escaping a command is printed by main() with exit code 2.

#include <string>
#include <vector>

namespace tessera::cli {

using Args = std::vector<std::string>;

int run_info(const Args& args);
int run_generate(const Args& args);
int run_solve(const Args& args);
int run_partition(const Args& args);
int run_launch(const Args& args);
int run_eval(const Args& args);
int run_plot(const Args& args);
int run_replay(const Args& args);

/// Removes --heap-pages VALUE (or --heap-pages=VALUE) from `args` and returns VALUE, "auto"
/// when absent. For `tessera launch`, whose flags go on to two parsers (batch and --online),
/// neither of which knows this process-level flag; `tessera solve` parses it with the rest.
std::string take_heap_pages_flag(Args& args);

/// The --heap-pages help line shared by solve and launch.
extern const char* const kHeapPagesHelp;

}  // namespace tessera::cli
