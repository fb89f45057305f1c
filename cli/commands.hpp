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

}  // namespace tessera::cli
