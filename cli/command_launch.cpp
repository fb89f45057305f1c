// `tessera launch`: runs a whole distributed solve on this host as separate processes, the
// coordinator and N agents talking over DDS (launch/launch.hpp does the work).

#include <cstdio>

#include "commands.hpp"
#include "launch/launch.hpp"

namespace tessera::cli {

int run_launch(const Args& argv) {
  if (launch::wants_launch_help(argv)) {
    std::fputs(launch::launch_help().c_str(), stdout);
    return 0;
  }
  return launch::launch(launch::parse_launch_options(argv)).exit_code;
}

}  // namespace tessera::cli
