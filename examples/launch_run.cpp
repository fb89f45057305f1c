// Run a whole distributed run over DDS on this host from your own program: the installed
// tessera-coordinator and AGENTS tessera-agent processes, as `tessera launch` starts them.
//   launch_run GRAPH.g2o AGENTS [DOMAIN]
// The executables are found through TESSERA_BINDIR, which CMakeLists.txt sets from the
// package's Tessera_BINDIR (so a package installed into any prefix works); without it,
// launch() looks next to this program, in the configured install prefix and on PATH.

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <tessera/dds/launch.hpp>
#include <tessera/util/input_error.hpp>

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: launch_run GRAPH.g2o AGENTS [DOMAIN]\n");
    return 2;
  }
  tessera::dds::LaunchOptions run;
  run.graph = argv[1];
  run.agents = std::atol(argv[2]);
  run.quiet = true;
  if (argc == 4) run.session.domain = std::atoi(argv[3]);
#ifdef TESSERA_BINDIR
  run.bin_dir = TESSERA_BINDIR;
#endif
  try {
    const tessera::dds::LaunchResult result = tessera::dds::launch(run);
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
